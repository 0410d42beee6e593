"""`astiop bench`: rank models on ROS knowledge (stage 1) and robot commands (stage 2)."""

from __future__ import annotations

import asyncio
import math
import sys
import time
from pathlib import Path

import typer

from astiop.cli.common import fail, print_json, state

app = typer.Typer(
    help="Benchmark LLMs: stage 1 ROS knowledge, stage 2 robot commands.", no_args_is_help=True
)


def _bar(done: int, total: int, width: int = 24) -> str:
    filled = int(width * done / total) if total else width
    return "█" * filled + "░" * (width - filled)


def _fmt_s(s: float) -> str:
    return f"{int(s // 60)}m{int(s % 60):02d}s"


@app.command("run")
def run_bench(
    ctx: typer.Context,
    stage: int = typer.Option(None, "--stage", help="1 (ROS knowledge) or 2 (robot commands)."),
    models: list[str] = typer.Option(None, "--model", "-m", help="Model spec; repeat for more."),
    mode: str = typer.Option("tool", help="Stage 2 reply mode: command, tool or both."),
    limit: int = typer.Option(None, help="Only the first N cases."),
    seed: int = typer.Option(0),
    timeout: float = typer.Option(120.0, help="Seconds a case may take."),
    max_tokens: int = typer.Option(384, help="Longest reply, in tokens."),
    concurrency: int = typer.Option(1, help="Cases at once, for servers that allow it."),
    interpretation: str = typer.Option(
        "grounded",
        "--interpretation",
        help="Stage 2 answers: grounded (checked against the results) or raw (as the paper).",
    ),
    resume: int = typer.Option(None, help="Finish an interrupted run by its id."),
    record: Path | None = typer.Option(
        None, "--record", help="Stage 2: record each case's simulator run as MCAP in this folder."
    ),
    protocol: str = typer.Option(
        "astiop",
        "--protocol",
        help="astiop (checked against the simulator), paper (the paper's scripts exactly), or "
        "both (stage 1).",
    ),
    suite: str | None = typer.Option(
        None, "--suite", help="A suite's name (astiop bench suites) or a suite file's path."
    ),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Run a benchmark; each case's result is stored as it finishes."""
    from astiop.agent.models.embedded import EmbeddedModelError
    from astiop.agent.models.specs import SpecError, parse_spec
    from astiop.bench import runner
    from astiop.bench.report import load_report

    st = state(ctx)
    store = st.store
    try:
        if resume is not None:
            config = runner.load_config(store, resume)
            run_id = resume
        else:
            if stage not in (1, 2):
                fail("--stage 1 or --stage 2 is required")
            if not models:
                fail("give at least one --model (e.g. --model rules --model embedded)")
            if mode not in ("command", "tool", "both"):
                fail("--mode is command, tool or both")
            if interpretation not in ("grounded", "raw"):
                fail("--interpretation is grounded or raw")
            if limit is not None and limit < 1:
                fail("--limit must be at least 1")
            if not 0 <= seed <= 2**32 - 1:
                fail("--seed must be within 0..4294967295")
            if not (math.isfinite(timeout) and 0 < timeout <= 86400):
                fail("--timeout must be a number of seconds within (0, 86400]")
            if concurrency < 1 or concurrency > 64:
                fail("--concurrency must be within 1..64")
            if not 1 <= max_tokens <= 32768:
                fail("--max-tokens must be within 1..32768")
            for spec in models:
                parse_spec(spec)
            if record is not None and stage != 2:
                fail("--record is for stage 2: only its cases drive the robot")
            if record is not None and st.settings.robot.backend != "sim":
                fail(
                    "--record is for the simulator's cases (record a live robot with astiop record)"
                )
            if record is not None:
                try:
                    record.mkdir(parents=True, exist_ok=True)
                except OSError as exc:
                    fail(f"--record {record}: {exc.strerror or exc}")
            modes = ["command", "tool"] if mode == "both" else [mode]
            if suite is not None and Path(suite).expanduser().is_file():
                suite = str(Path(suite).expanduser().resolve())  # a resume finds it again
            config = runner.RunConfig(
                stage,
                list(dict.fromkeys(models)),
                modes,
                limit,
                seed,
                timeout,
                max_tokens,
                concurrency,
                interpretation,
                str(record.resolve()) if record is not None else None,
                protocol,
                suite,
                robot=st.settings.robot.backend if stage == 2 else "sim",
            )
            run_id = runner.create_run(store, config)
    except (runner.BenchError, SpecError) as exc:
        fail(str(exc))

    def progress(p: runner.Progress) -> None:
        if not as_json:
            typer.echo(
                f"\r{_bar(p.done, p.total)} {p.done}/{p.total} {p.model} {p.mode} "
                f"{p.case_id} {p.outcome:<7} ETA {_fmt_s(p.eta_s)}   ",
                err=True,
                nl=p.done == p.total,
            )

    if not as_json:
        typer.echo(
            f"benchmark run {run_id}: stage {config.stage}, models {', '.join(config.models)}",
            err=True,
        )
    t0 = time.perf_counter()
    try:
        asyncio.run(runner.run(store, st.settings, config, run_id, progress))
    except KeyboardInterrupt:
        store.end_bench_run(run_id, "interrupted")
        typer.echo(
            f"\ninterrupted; finished cases are stored. Resume with: astiop bench run "
            f"--resume {run_id}",
            err=True,
        )
        raise typer.Exit(130) from None
    except EmbeddedModelError as exc:
        fail(str(exc))
    rep = load_report(store, run_id)
    if as_json:
        data = rep.as_json()
        print_json(
            {
                "run_id": run_id,
                "stage": config.stage,
                "results": [
                    {
                        k: r[k]
                        for k in (
                            "model",
                            "mode",
                            "components",
                            "composite",
                            "cases",
                            "errors",
                            "timeouts",
                        )
                    }
                    for r in data["results"]
                ],
            }
        )
        return
    from astiop.bench.report import to_markdown

    typer.echo(to_markdown(rep, cases=False))
    typer.echo(
        f"wall time {time.perf_counter() - t0:.1f} s; astiop bench report {run_id}", err=True
    )


@app.command("list")
def list_cmd(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List benchmark runs."""
    from astiop.bench.report import list_runs

    runs = list_runs(state(ctx).store)
    if as_json:
        print_json(runs)
        return
    if not runs:
        typer.echo("no benchmark runs yet (astiop bench run --stage 2 --model rules)")
        return
    for r in runs:
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(r["started_at"]))
        typer.echo(
            f"{r['id']:>4}  {when}  stage {r['stage']}  {r['status']:<11} "
            f"{r['results']:>4} results  {', '.join(r['models'])} "
            f"({', '.join(r['modes'])})"
        )


@app.command("report")
def report_cmd(
    ctx: typer.Context,
    run_id: int = typer.Argument(..., help="The run's id (astiop bench list)."),
    fmt: str = typer.Option("md", "--format", "-f", help="md, csv, json or jsonl."),
    figures: Path | None = typer.Option(
        None,
        "--figures",
        help='Also draw the paper\'s figure kinds here (SVG, PNG; needs "astiop[plots]").',
    ),
) -> None:
    """A run's rankings, breakdowns and every case (prompt, response, scores): Markdown, or
    every case as CSV, JSON (with the rankings) or JSON lines."""
    from astiop.bench.report import load_report, to_csv, to_json, to_jsonl, to_markdown
    from astiop.bench.runner import BenchError

    formats = {"md": to_markdown, "csv": to_csv, "json": to_json, "jsonl": to_jsonl}
    if fmt not in formats:
        fail("--format is md, csv, json or jsonl")
    try:
        rep = load_report(state(ctx).store, run_id)
    except BenchError as exc:
        fail(str(exc))
    if figures is not None:
        from astiop.bench.figures import FiguresUnavailable, write_figures

        try:
            written = write_figures(rep, figures)
        except FiguresUnavailable as exc:
            fail(str(exc))
        except OSError as exc:
            fail(f"cannot write figures to {figures}: {exc.strerror or exc}")
        typer.echo(f"{len(written)} figure files in {figures}", err=True)
    text = formats[fmt](rep)
    sys.stdout.write(text if text.endswith("\n") else text + "\n")


@app.command("import")
def import_cmd(
    ctx: typer.Context,
    paths: list[Path] = typer.Argument(
        ..., help="The paper's test_ros_agents.py / test_ros_command_agent.py, or suite YAML files."
    ),
) -> None:
    """Import benchmark suites: the paper's two scripts (read with ast, never run) become
    paper-stage1 and paper-stage2; an astiop suite file is checked and kept by its name."""
    from astiop.bench.paper_import import import_suite
    from astiop.bench.suites import SuiteError

    data_dir = state(ctx).db_path.parent
    for path in paths:
        try:
            suite, out = import_suite(path, data_dir)
        except SuiteError as exc:
            fail(str(exc))
        typer.echo(f"{suite.name}: stage {suite.stage}, {len(suite.cases)} cases -> {out}")


@app.command("suites")
def suites_cmd(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """The suites bench run can use: built in and imported."""
    from astiop.bench.library import all_suites

    found, problems = all_suites(state(ctx).db_path.parent)
    rows = [
        {"name": s.name, "stage": s.stage, "kind": s.kind, "cases": len(s.cases),
         "source": s.source, "path": s.path}
        for s in found
    ]  # fmt: skip
    if as_json:
        print_json({"suites": rows, "unreadable": problems})
        return
    for r in rows:
        typer.echo(
            f"{r['name']:<16} stage {r['stage']}  {r['kind']:<9} {r['cases']:>4} cases  {r['source']}"
        )
    for why in problems:
        typer.echo(f"unreadable: {why}", err=True)
