"""Bench: run the two-stage benchmark and read rankings, components and per-category maps."""

from __future__ import annotations

import time

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.widgets import (
    Button,
    DataTable,
    Footer,
    Header,
    Input,
    Label,
    ProgressBar,
    Select,
    Static,
)

from astiop.agent.models.specs import SpecError, parse_spec
from astiop.bench import runner
from astiop.bench.library import all_suites, load_suite
from astiop.bench.report import SIDE_FIGURES, Report, list_runs, load_report
from astiop.bench.suites import SuiteError
from astiop.screens.base import ConsoleScreen
from astiop.widgets.gauges import bar

HEAT = ["#7f1d1d", "#b45309", "#a16207", "#4d7c0f", "#15803d"]


def heat(value: float) -> Text:
    colour = HEAT[min(int(value / 20.0001), 4)]
    return Text(f"{value:5.0f}", style=f"bold white on {colour}")


class BenchScreen(ConsoleScreen):
    BINDINGS = [Binding("ctrl+b", "run", "Run"), Binding("ctrl+l", "reload", "Reload runs")]

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Horizontal(id="bench-controls"):
            suites, _ = all_suites(self.services.store.path.parent)
            yield Select(
                [(f"{s.name} ({len(s.cases)})", s.name) for s in suites],
                value="astiop-stage2",
                allow_blank=False,
                id="bench-suite",
            )
            yield Select(
                [("astiop", "astiop"), ("paper", "paper"), ("both", "both")],
                value="astiop",
                allow_blank=False,
                id="bench-protocol",
            )
            yield Input(
                value="rules, embedded", placeholder="models, comma-separated", id="bench-models"
            )
            yield Select(
                [("tool mode", "tool"), ("command mode", "command"), ("both modes", "both")],
                value="tool",
                allow_blank=False,
                id="bench-mode",
            )
            yield Input(placeholder="limit (all)", id="bench-limit")
            yield Button("Run (ctrl+b)", id="bench-run", variant="primary")
        with Horizontal(id="bench-progress-row"):
            yield ProgressBar(total=1, id="bench-progress", show_eta=False)
            yield Label("", id="bench-status")
        with Horizontal(id="bench-body"):
            yield DataTable(id="bench-runs", cursor_type="row")
            with VerticalScroll(id="bench-report"):
                yield DataTable(id="bench-ranking", cursor_type="none")
                yield Static(id="bench-bars", classes="panel")
                yield DataTable(id="bench-heat", cursor_type="none")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#bench-runs", DataTable).add_columns("run", "stage", "status", "models")

    def on_screen_resume(self) -> None:
        self.action_reload()

    def action_reload(self) -> None:
        self.runs = list_runs(self.services.store)
        table = self.query_one("#bench-runs", DataTable)
        table.clear()
        for r in self.runs:
            table.add_row(str(r["id"]), str(r["stage"]), r["status"], Text(", ".join(r["models"])))
        if self.runs:
            self.show_report(self.runs[0]["id"])
        else:
            self.query_one("#bench-bars", Static).update(
                "No benchmark runs yet: choose the suite, the protocol, the models "
                "(comma-separated specs) and the mode, then press ctrl+b. Runs from "
                "`astiop bench run` show here too; `astiop bench import` adds the paper's suites."
            )

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        if event.data_table.id == "bench-runs" and 0 <= event.cursor_row < len(self.runs):
            self.show_report(self.runs[event.cursor_row]["id"])

    def on_button_pressed(self, event: Button.Pressed) -> None:
        if event.button.id == "bench-run":
            self.action_run()

    def _config(self) -> runner.RunConfig | None:
        models = [
            m.strip() for m in self.query_one("#bench-models", Input).value.split(",") if m.strip()
        ]
        if not models:
            self.notify("name at least one model", severity="error")
            return None
        try:
            for m in models:
                parse_spec(m)
        except SpecError as exc:
            self.notify(str(exc), severity="error", markup=False)
            return None
        limit_text = self.query_one("#bench-limit", Input).value.strip()
        if limit_text and (not limit_text.isdigit() or int(limit_text) < 1):
            self.notify("limit is a whole number of cases", severity="error")
            return None
        mode = self.query_one("#bench-mode", Select).value
        store = self.services.store
        try:
            suite = load_suite(self.query_one("#bench-suite", Select).value, store.path.parent)
            config = runner.RunConfig(
                stage=suite.stage,
                models=models,
                modes=["command", "tool"] if mode == "both" else [mode],
                limit=int(limit_text) if limit_text else None,
                protocol=self.query_one("#bench-protocol", Select).value,
                suite=suite.name,
            )
            runner.suite_of(store, config)  # the suite, protocol and models fit together
        except (SuiteError, runner.BenchError) as exc:
            self.notify(str(exc), severity="error", markup=False)
            return None
        return config

    def action_run(self) -> None:
        config = self._config()
        if config is not None:
            self.run_bench(config)

    @work(exclusive=True, group="bench", exit_on_error=False)
    async def run_bench(self, config: runner.RunConfig) -> None:
        store = self.services.store
        run_id = runner.create_run(store, config)
        progress = self.query_one("#bench-progress", ProgressBar)
        status = self.query_one("#bench-status", Label)
        progress.update(total=None, progress=0)
        status.update(f"run {run_id}: starting…")
        t0 = time.perf_counter()

        def on_progress(p: runner.Progress) -> None:
            progress.update(total=p.total, progress=p.done)
            status.update(
                f"run {run_id}: {p.done}/{p.total}  {p.model} {p.mode} {p.case_id} "
                f"{p.outcome}  ETA {p.eta_s:.0f} s"
            )

        await runner.run(store, self.services.settings, config, run_id, on_progress)
        status.update(f"run {run_id} done in {time.perf_counter() - t0:.0f} s")
        self.action_reload()

    def show_report(self, run_id: int) -> None:
        rep: Report = load_report(self.services.store, run_id)
        ranking = self.query_one("#bench-ranking", DataTable)
        ranking.clear(columns=True)
        bars = self.query_one("#bench-bars", Static)
        heatmap = self.query_one("#bench-heat", DataTable)
        heatmap.clear(columns=True)
        if not rep.results:
            bars.update(f"run {run_id}: no results yet")
            return
        comps = [k for k in rep.results[0].components if k not in SIDE_FIGURES]
        ranking.add_columns("#", "model", "mode", *comps, "composite", "err", "t/o")
        for i, r in enumerate(rep.results, 1):
            ranking.add_row(
                str(i),
                Text(r.model),
                r.mode,
                *[f"{r.components[k]:.1f}" for k in comps],
                Text(f"{r.composite:.1f}", style="bold"),
                str(r.errors),
                str(r.timeouts),
            )
        # each dimension as an axis, every model's bar on it: what a radar chart shows
        text = Text(f"run {run_id} · stage {rep.stage} · {rep.status}\n", style="bold")
        width = max(len(f"{r.model}/{r.mode}") for r in rep.results)
        for k in comps + ["composite"]:
            text.append(f"{k}\n", style="bold")
            for r in rep.results:
                v = r.composite if k == "composite" else r.components[k]
                text += Text(f"  {f'{r.model}/{r.mode}':<{width}} ") + bar(v / 100, 30, "cyan")
                text.append(f" {v:5.1f}\n")
        bars.update(text)
        cats = sorted({c for r in rep.results for c in r.by_category})
        heatmap.add_columns("model", *cats)
        for r in rep.results:
            heatmap.add_row(
                Text(f"{r.model}/{r.mode}"), *[heat(r.by_category.get(c, 0.0)) for c in cats]
            )
