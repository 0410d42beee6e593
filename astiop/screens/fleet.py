"""Fleet (F7): every robot of the fleet, live — a table of what each reported and a map with
each drawn and named. The current robot (the one Dashboard, Chat, Teleop and Locations act on)
is marked; ctrl+e stops them all."""

from __future__ import annotations

import math
from collections import Counter

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.widgets import DataTable, Footer, Header, Static

from astiop.robot.fleet_watch import FleetRow
from astiop.screens import control
from astiop.screens.base import ConsoleScreen
from astiop.screens.modals import ConfirmModal
from astiop.widgets.map_canvas import MapCanvas, Place

SORTS = ("name", "battery", "state", "age")
FILTERS = ("all", "low battery", "stale")
REFRESH_S = 0.5


class FleetMapView(MapCanvas):
    markers_are = "robots"


def _sorted(rows: list[FleetRow], by: str) -> list[FleetRow]:
    if by == "battery":  # lowest first; none read last
        return sorted(rows, key=lambda r: (r.battery is None, r.battery or 0.0, r.name))
    if by == "state":
        return sorted(rows, key=lambda r: (r.state, r.name))
    if by == "age":  # the least recently heard first
        return sorted(rows, key=lambda r: -(r.age_s if r.age_s is not None else math.inf))
    return sorted(rows, key=lambda r: r.name)


def _kept(rows: list[FleetRow], by: str) -> list[FleetRow]:
    if by == "low battery":
        return [r for r in rows if r.low_battery]
    if by == "stale":
        return [r for r in rows if r.stale]
    return rows


def counts(rows: list[FleetRow]) -> str:
    """'5 robots: 3 charging, 1 navigating, 1 e_stopped; 1 stale'."""
    by_state = Counter(r.state for r in rows)
    text = f"{len(rows)} robot{'s' if len(rows) != 1 else ''}: " + ", ".join(
        f"{n} {state}" for state, n in sorted(by_state.items())
    )
    stale = sum(r.stale for r in rows)
    return text + (f"; {stale} stale" if stale else "")


def _cells(row: FleetRow, current: bool, controller: str) -> list:
    bad = row.error or row.state in ("e_stopped", "fault", "lost")
    style = "bold red" if bad else ("yellow" if row.stale or row.low_battery else "")
    mark = "▶ " if current else "  "
    age = "never" if row.age_s is None else f"{row.age_s:.1f} s"
    pose = "-" if row.x is None else f"{row.x:.2f}, {row.y:.2f}"
    battery = "-" if row.battery is None else f"{row.battery * 100:.1f} %"
    speed = "-" if row.speed is None else f"{row.speed:.2f} m/s"
    state = row.error or row.state
    return [
        Text(mark + row.name, style="bold" if current else ""),
        Text(state, style=style),
        Text(battery, style="yellow" if row.low_battery else ""),
        pose,
        speed,
        Text(row.goal or "-"),
        Text(age, style="yellow" if row.stale else ""),
        controller,
    ]


class FleetScreen(ConsoleScreen):
    DEFAULT_CSS = """
    FleetScreen #fleet-table { width: 3fr; }
    FleetScreen #fleet-map { width: 2fr; }
    """
    BINDINGS = [
        Binding("enter", "use_robot", "Make current", show=True),
        Binding("x", "stop_one", "E-STOP this robot"),
        Binding("r", "release_one", "Release it"),
        Binding("s", "sort", "Sort"),
        Binding("f", "filter", "Filter"),
    ]

    def __init__(self):
        super().__init__()
        self.sort_by = SORTS[0]
        self.filter_by = FILTERS[0]
        self.shown: list[FleetRow] = []

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        yield Static(id="fleet-current")
        with Horizontal():
            yield DataTable(id="fleet-table", cursor_type="row", zebra_stripes=True)
            yield FleetMapView(self.services.gateway.map_geometry(), id="fleet-map")
        yield Footer()

    def on_mount(self) -> None:  # ConsoleScreen's runs too (Textual calls each class's own)
        self.query_one(DataTable).add_columns(
            "robot", "state", "battery", "x, y (m)", "speed", "goal", "heard", "control"
        )
        self.refresh_rows()
        self.set_interval(REFRESH_S, self.refresh_rows)

    def refresh_rows(self) -> None:
        app = self.app
        rows = app.fleet_rows()  # type: ignore[attr-defined]
        current = app.current_robot  # type: ignore[attr-defined]
        self.shown = _sorted(_kept(rows, self.filter_by), self.sort_by)
        table = self.query_one(DataTable)
        cursor = table.cursor_row
        table.clear()
        for row in self.shown:
            table.add_row(*_cells(row, row.name == current, row.control or "-"))
        if self.shown:
            table.move_cursor(row=min(cursor, len(self.shown) - 1))
        shown = "" if self.filter_by == "all" else f" ({len(self.shown)} {self.filter_by})"
        self.sub_title = f"{counts(rows)}{shown}; sorted by {self.sort_by}"
        self.query_one("#fleet-current", Static).update(
            Text(
                f"current robot: {current}  (Dashboard, Chat, Teleop and Locations act on it)",
                style="bold",
            )  # fmt: skip
        )
        places = [Place(r.name, r.x, r.y) for r in rows if r.x is not None]
        self.query_one(FleetMapView).set_locations(places)

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        self.action_use_robot()

    def action_use_robot(self) -> None:
        """The row under the cursor becomes the current robot."""
        table = self.query_one(DataTable)
        if not self.shown or table.cursor_row < 0:
            return
        control.use_robot(self.app, self.shown[min(table.cursor_row, len(self.shown) - 1)].name)
        self.refresh_rows()

    def action_sort(self) -> None:
        self.sort_by = SORTS[(SORTS.index(self.sort_by) + 1) % len(SORTS)]
        self.refresh_rows()

    def action_filter(self) -> None:
        self.filter_by = FILTERS[(FILTERS.index(self.filter_by) + 1) % len(FILTERS)]
        self.refresh_rows()

    def _selected(self) -> str | None:
        table = self.query_one(DataTable)
        if not self.shown or table.cursor_row < 0:
            return None
        return self.shown[min(table.cursor_row, len(self.shown) - 1)].name

    def action_stop_one(self) -> None:
        """x: the robot under the cursor stopped and latched (no question: a stop)."""
        name, fleet = self._selected(), self.app.fleet  # type: ignore[attr-defined]
        if name is None or fleet is None:
            return

        def stop() -> None:
            failures = fleet.estop(name)
            said = f"E-STOP engaged on {name}." + "".join(f"\n{f}" for f in failures)
            self.app.call_from_thread(
                self.app.notify, said, severity="error", title="E-STOP", markup=False
            )

        self.run_worker(stop, thread=True, group="estop", exit_on_error=False)

    def action_release_one(self) -> None:
        """r: the robot under the cursor released, once the operator said so."""
        name, fleet = self._selected(), self.app.fleet  # type: ignore[attr-defined]
        if name is None or fleet is None:
            return

        def release() -> None:
            failures = fleet.release(name)
            said = f"{name}: " + ("; ".join(failures) if failures else "E-STOP released.")
            self.app.call_from_thread(
                self.app.notify, said, severity="error" if failures else "information",
                markup=False,
            )  # fmt: skip

        def done(ok: bool | None) -> None:
            if ok:
                self.run_worker(release, thread=True, group="estop", exit_on_error=False)

        question = f"Release the E-STOP of {name}? It may move again."
        self.app.push_screen(ConfirmModal(question), done)
