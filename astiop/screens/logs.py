"""Logs: every interaction, robot event and alert from the store, filtered, exportable."""

from __future__ import annotations

import csv
import json
import time
from pathlib import Path

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import DataTable, Footer, Header, Input, Select, Static

from astiop.bounded import escape_controls
from astiop.screens.base import ConsoleScreen
from astiop.watches.alert_text import reading_text, when

KINDS = [
    ("all rows", "all"),
    ("interactions", "interaction"),
    ("robot events", "event"),
    ("alerts", "alert"),
]
VALIDITY = [
    ("any validity", "any"),
    ("all valid", "valid"),
    ("some rejected", "invalid"),
]


class LogsScreen(ConsoleScreen):
    BINDINGS = [
        Binding("ctrl+l", "reload", "Reload"),
        Binding("x", "export('csv')", "CSV"),
        Binding("j", "export('json')", "JSON"),
    ]

    def __init__(self):
        super().__init__()
        self.rows: list[dict] = []
        self.shown: list[dict] = []

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Horizontal(id="logs-filters"):
            yield Input(placeholder="search prompt, answer, command…", id="logs-search")
            yield Select(KINDS, value="all", allow_blank=False, id="logs-kind")
            yield Select(VALIDITY, value="any", allow_blank=False, id="logs-valid")
            yield Select([("any model", "any")], value="any", allow_blank=False, id="logs-model")
            yield Select([("any robot", "any")], value="any", allow_blank=False, id="logs-robot")
        with Horizontal(id="logs-body"):
            yield DataTable(id="logs-table", cursor_type="row", zebra_stripes=True)
            yield VerticalScroll(Static(id="logs-detail-text", markup=False), id="logs-detail")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one(DataTable).add_columns("when", "kind", "model", "valid", "summary")

    def on_screen_resume(self) -> None:
        self.action_reload()

    @work(thread=True, exclusive=True, group="logs", exit_on_error=False)
    def action_reload(self) -> None:
        store = self.services.store
        rows = []
        interactions = store.interactions(500)
        commands = store.commands_by_interaction([it["id"] for it in interactions])
        for it in interactions:
            cmds = commands[it["id"]]
            rows.append(
                {
                    "kind": "interaction",
                    "robot": it.get("robot") or "",
                    "t": it["started_at"],
                    "model": it["model"],
                    "valid": all(c["valid"] for c in cmds) if cmds else None,
                    "summary": it["prompt"],
                    "record": it,
                    "commands": cmds,
                }
            )
        for ev in store.events(500):
            rows.append(
                {
                    "kind": "event",
                    "robot": ev.get("robot") or "",
                    "t": ev["t"],
                    "model": "",
                    "valid": None,
                    "summary": f"[{ev['severity']}] {ev['kind']}: {ev['message']}",
                    "record": ev,
                    "commands": [],
                }
            )
        for a in store.alerts_where(limit=500):  # every process's, as the Alerts screen (F8)
            seen = f"acknowledged by {a['acknowledged_by']}" if a["acknowledged_at"] else "open"
            rows.append(
                {
                    "kind": "alert",
                    "robot": a["robot"] or "",
                    "t": a["fired_at"],
                    "model": "",
                    "valid": None,
                    "summary": f"[{a['kind']}] {a['message']} ({seen})",
                    "record": a,
                    "commands": [],
                }
            )
        rows.sort(key=lambda r: r["t"], reverse=True)
        self.app.call_from_thread(self._loaded, rows)

    def _loaded(self, rows: list[dict]) -> None:
        self.rows = rows
        models = sorted({r["model"] for r in rows if r["model"]})
        select = self.query_one("#logs-model", Select)
        current = select.value
        select.set_options([("any model", "any")] + [(m, m) for m in models])
        select.value = current if current in models else "any"
        robots = sorted({r["robot"] for r in rows if r["robot"]})  # a fleet's, by name
        select = self.query_one("#logs-robot", Select)
        current = select.value
        select.set_options([("any robot", "any")] + [(name, name) for name in robots])
        select.value = current if current in robots else "any"
        self._filter()

    def on_input_changed(self) -> None:
        self._filter()

    def on_select_changed(self) -> None:
        self._filter()

    def _matches(self, r: dict) -> bool:
        kind = self.query_one("#logs-kind", Select).value
        valid = self.query_one("#logs-valid", Select).value
        model = self.query_one("#logs-model", Select).value
        robot = self.query_one("#logs-robot", Select).value
        text = self.query_one("#logs-search", Input).value.lower().strip()
        if kind != "all" and r["kind"] != kind:
            return False
        if model != "any" and r["model"] != model:
            return False
        if robot != "any" and r["robot"] != robot:
            return False
        if valid == "valid" and r["valid"] is not True:
            return False
        if valid == "invalid" and r["valid"] is not False:
            return False
        if text:
            hay = " ".join(
                [r["summary"], str(r["record"].get("answer") or "")]
                + [c["command"] for c in r["commands"]]
            ).lower()
            return text in hay
        return True

    def _filter(self) -> None:
        table = self.query_one(DataTable)
        table.clear()
        self.shown = [r for r in self.rows if self._matches(r)]
        for r in self.shown:
            valid = "-" if r["valid"] is None else ("yes" if r["valid"] else "NO")
            # stored text is data, never markup: "[/scan]" prints as typed
            table.add_row(
                when(r["t"]),
                r["kind"] if not r["robot"] else f"{r['kind']} · {r['robot']}",
                Text(escape_controls(r["model"])),
                valid,
                Text(escape_controls(r["summary"][:80])),
            )
        self.sub_title = f"{len(self.shown)} of {len(self.rows)} rows"
        if self.shown:
            self._detail(self.shown[0])

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if 0 <= event.cursor_row < len(self.shown):
            self._detail(self.shown[event.cursor_row])

    def _detail(self, r: dict) -> None:
        rec = r["record"]
        if r["kind"] == "event":
            text = (
                f"{when(rec['t'])}  sim t {rec['sim_t']}\n{rec['severity']} {rec['kind']}\n"
                f"{rec['message']}"
            )
        elif r["kind"] == "alert":
            reading = reading_text(rec)
            seen = (
                f"acknowledged by {rec['acknowledged_by']} at {when(rec['acknowledged_at'])}"
                if rec["acknowledged_at"]
                else "open (acknowledged on the Alerts screen, F8)"
            )
            watch = f"  watch {rec['watch_id']}" if rec["watch_id"] is not None else ""
            text = (
                f"{when(rec['fired_at'])}  {rec['robot'] or 'the robot'}  {rec['kind']}{watch}\n"
                f"{rec['message']}\nreading: {reading}\n{seen}"
            )
        else:
            lines = [
                f"prompt: {rec['prompt']}",
                f"model: {rec['model']}  mode: {rec['mode']}",
                f"status: {rec['status']}  total {rec['total_s'] or 0:.2f} s  "
                f"ttft {rec['ttft_s'] or 0:.2f} s  tokens {rec['prompt_tokens']}/"
                f"{rec['completion_tokens']}",
            ]
            if rec["error"]:
                lines.append(f"error: {rec['error']}")
            for c in r["commands"]:
                mark = "✓" if c["executed"] else "✗"
                lines += ["", f"{mark} {c['command']}"]
                if c["reason"]:
                    lines.append(f"  reason: {c['reason']}")
                if c["output"]:
                    lines.append("  " + c["output"].strip()[:800].replace("\n", "\n  "))
            lines += ["", f"answer: {rec['answer']}", "", "raw replies:"]
            lines += [f"  {raw}" for raw in json.loads(rec["raw_replies"] or "[]")]
            text = "\n".join(lines)
        self.query_one("#logs-detail-text", Static).update(text)

    @work(thread=True, group="export", exit_on_error=False)
    def action_export(self, fmt: str) -> None:
        folder = self.services.store.path.parent / "exports"
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"astiop-logs-{time.strftime('%Y%m%d-%H%M%S')}.{fmt}"
        records = [
            {
                "kind": r["kind"],
                "when": when(r["t"]),
                "model": r["model"],
                "valid": r["valid"],
                "summary": r["summary"],
                "answer": r["record"].get("answer"),
                "commands": [c["command"] for c in r["commands"]],
            }
            for r in self.shown
        ]
        _write(path, fmt, records)
        self.app.call_from_thread(
            self.notify, f"exported {len(records)} rows to {path}", markup=False
        )


def _write(path: Path, fmt: str, records: list[dict]) -> None:
    if fmt == "json":
        path.write_text(json.dumps(records, indent=2, default=str), encoding="utf-8")
        return
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(
            fh, fieldnames=["kind", "when", "model", "valid", "summary", "answer", "commands"]
        )
        writer.writeheader()
        for r in records:
            writer.writerow({**r, "commands": " | ".join(r["commands"])})
