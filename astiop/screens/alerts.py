"""Alerts (F8): what the watches and the built-in alerts fired, on every robot and from every
process on this database, newest first — open ones until acknowledged, then by whom and when.
Filter by robot, kind and open/acknowledged; `a` acknowledges the selected alert."""

from __future__ import annotations

import os
import socket

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.widgets import DataTable, Footer, Header, Select, Static

from astiop.screens.base import ConsoleScreen
from astiop.watches.alert_text import reading_text, when
from astiop.watches.builtins import KINDS

POLL_S = 1.0  # another process's alert or acknowledgement shows within this
SHOWN = 500
STATES = [("open", "open"), ("acknowledged", "acked"), ("open and acknowledged", "all")]
COLUMNS = (  # fit 120 columns: the acknowledgement is never scrolled out of sight
    ("#", 4), ("fired", 14), ("robot", 10), ("kind", 14), ("what", 30), ("reading", 12),
    ("acknowledged", None),
)  # fmt: skip
SEVERE = ("estop", "fault", "contact_lost", "goal_aborted", "mission_failed", "no_progress")


def _cells(a: dict) -> list:
    acked = a["acknowledged_at"] is not None
    style = "dim" if acked else ("bold red" if a["kind"] in SEVERE else "yellow")
    reading = reading_text(a)
    ack = f"{a['acknowledged_by']} at {when(a['acknowledged_at'])}" if acked else "open"
    return [
        str(a["id"]),
        when(a["fired_at"]),
        Text(a["robot"] or "-"),
        Text(a["kind"], style=style),
        Text(a["message"]),
        Text(reading),
        Text(ack, style="" if acked else "bold"),
    ]


class AlertsScreen(ConsoleScreen):
    DEFAULT_CSS = """
    AlertsScreen #alerts-filters { height: 3; }
    AlertsScreen #alerts-filters Select { width: 1fr; }
    AlertsScreen #alerts-count { height: 1; padding: 0 1; }
    AlertsScreen #alerts-table { height: 1fr; }
    AlertsScreen #alerts-detail { height: auto; max-height: 6; padding: 0 1; border-top: solid $primary; }
    """
    BINDINGS = [
        Binding("a", "acknowledge", "Acknowledge"),
        Binding("ctrl+l", "reload", "Reload"),
    ]

    def __init__(self):
        super().__init__()
        self.shown: list[dict] = []
        self._version: tuple[int, float] | None = None
        self._robots: list[str] = []

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Horizontal(id="alerts-filters"):
            yield Select([("any robot", "any")], value="any", allow_blank=False, id="alerts-robot")
            kinds = [("any kind", "any"), *((k, k) for k in ("watch", *KINDS))]
            yield Select(kinds, value="any", allow_blank=False, id="alerts-kind")
            yield Select(STATES, value="open", allow_blank=False, id="alerts-state")
        yield Static(id="alerts-count", markup=False)
        yield DataTable(id="alerts-table", cursor_type="row", zebra_stripes=True)
        yield Static(id="alerts-detail", markup=False)
        yield Footer()

    def on_mount(self) -> None:
        table = self.query_one(DataTable)
        for label, width in COLUMNS:
            table.add_column(label, width=width)
        self.set_interval(POLL_S, self._tick)

    def _tick(self) -> None:
        """A look at the store while shown, one at a time (a slow one is not cancelled)."""
        busy = any(w.group == "alerts-poll" and w.is_running for w in self.workers)
        if self.is_current and not busy:
            self._poll()

    def on_screen_resume(self) -> None:
        self.query_one(DataTable).focus()  # `a` acknowledges from the first key
        self.action_reload()

    def on_select_changed(self, _event: Select.Changed) -> None:
        self.action_reload()

    def _filters(self) -> tuple[str | None, str | None, str]:
        robot = self.query_one("#alerts-robot", Select).value
        kind = self.query_one("#alerts-kind", Select).value
        state = self.query_one("#alerts-state", Select).value
        return (
            None if robot == "any" else str(robot),
            None if kind == "any" else str(kind),
            str(state),
        )

    @work(thread=True, group="alerts-poll", exit_on_error=False)
    def _poll(self) -> None:
        """Reloaded when any process wrote or acknowledged an alert since the last look."""
        version = self.services.store.alerts_version()
        if version != self._version:
            self._load(*self.app.call_from_thread(self._filters), version)

    @work(thread=True, exclusive=True, group="alerts", exit_on_error=False)
    def action_reload(self) -> None:
        store = self.services.store
        self._load(*self.app.call_from_thread(self._filters), store.alerts_version())

    def _load(self, robot, kind, state: str, version) -> None:
        store = self.services.store
        rows = store.alerts_where(robot, kind, open_only=state == "open", limit=SHOWN)
        if state == "acked":
            rows = [r for r in rows if r["acknowledged_at"] is not None]
        robots = store.alert_robots()
        self.app.call_from_thread(self._show, rows, robots, version)

    def _show(self, rows: list[dict], robots: list[str], version) -> None:
        self._version = version
        if robots != self._robots:
            self._robots = robots
            select = self.query_one("#alerts-robot", Select)
            chosen = select.value
            with select.prevent(Select.Changed):
                select.set_options([("any robot", "any"), *((r or "-", r) for r in robots)])
                select.value = chosen if chosen == "any" or chosen in robots else "any"
        table = self.query_one(DataTable)
        keep = self.shown[table.cursor_row]["id"] if self.shown and table.row_count else None
        self.shown = rows
        table.clear()
        for a in rows:
            table.add_row(*_cells(a), key=str(a["id"]))
        ids = [a["id"] for a in rows]
        if keep in ids:
            table.move_cursor(row=ids.index(keep))
        open_ = sum(a["acknowledged_at"] is None for a in rows)
        self.query_one("#alerts-count", Static).update(
            f"{len(rows)} alert{'s' if len(rows) != 1 else ''} shown, {open_} open"
            + ("  (a: acknowledge the selected one)" if open_ else "")
        )

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        """The selected alert whole: the table cuts a long message short."""
        row = event.cursor_row
        if not 0 <= row < len(self.shown):
            return
        a = self.shown[row]
        cells = _cells(a)
        said = f"alert {a['id']} on {cells[2]} at {cells[1]}: {a['message']}\nreading: {cells[5]}"
        self.query_one("#alerts-detail", Static).update(f"{said}\nacknowledged: {cells[6]}")

    def action_acknowledge(self) -> None:
        table = self.query_one(DataTable)
        if not self.shown or table.row_count == 0:
            self.notify("no alert selected", severity="warning")
            return
        alert = self.shown[table.cursor_row]
        if alert["acknowledged_at"] is not None:
            self.notify(f"alert {alert['id']} was acknowledged by {alert['acknowledged_by']}")
            return
        self._acknowledge(alert["id"])

    @work(thread=True, group="alerts-ack", exit_on_error=False)
    def _acknowledge(self, alert_id: int) -> None:
        who = f"{self.services.gateway.who} on {socket.gethostname()} (pid {os.getpid()})"
        done = self.services.store.acknowledge_alert(alert_id, who)
        said = (
            f"alert {alert_id} acknowledged" if done else f"alert {alert_id}: acknowledged already"
        )
        self.app.call_from_thread(self.notify, said, markup=False)
        self.app.call_from_thread(self.action_reload)
