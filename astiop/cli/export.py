"""`astiop export session`: a stretch of time from the store and the recordings, as one file."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from astiop.cli.common import fail, print_json, state

app = typer.Typer(help="Export what astiop keeps.", no_args_is_help=True)


@app.command("session")
def session(
    ctx: typer.Context,
    since: str = typer.Option(
        "-1h", "--from", help="Start: now, -10m, -2h, 14:05, 2026-11-22T14:05 or epoch seconds."
    ),
    until: str = typer.Option("now", "--to", help="End, in the same forms."),
    fmt: str | None = typer.Option(
        None, "--format", help="mcap or jsonl (default: from --output's suffix, else mcap)."
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="The file (default: <data dir>/exports/session-<from>.<ext>)."
    ),
    recordings: Path | None = typer.Option(
        None, "--recordings", help="Where the recordings are (default: <data dir>/sessions)."
    ),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """The agent's turns and the robot's events from the store, and the robot's messages from
    every recording that covers the stretch, in wall-clock order."""
    from astiop.recording.export import (
        ExportError,
        export_jsonl,
        export_mcap,
        parse_time,
        recordings_between,
    )

    if fmt is None:
        fmt = "jsonl" if output is not None and output.suffix == ".jsonl" else "mcap"
    if fmt not in ("mcap", "jsonl"):
        fail(f"--format must be mcap or jsonl, not '{fmt}'")
    now = time.time()
    try:
        t0, t1 = parse_time(since, now), parse_time(until, now)
    except ExportError as exc:
        fail(str(exc))
    if t1 < t0:
        fail(f"--to ({until}) is before --from ({since})")
    st = state(ctx)
    folder = recordings or st.db_path.parent / "sessions"
    if recordings is not None and not recordings.is_dir():
        fail(f"--recordings {recordings}: no such folder")
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(t0))
    out = output or st.db_path.parent / "exports" / f"session-{stamp}.{fmt}"
    found, skipped = recordings_between(folder, t0, t1, exclude=out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        export = export_mcap if fmt == "mcap" else export_jsonl
        counts = export(out, st.store, found, t0, t1)
    except OSError as exc:
        fail(f"cannot write {out}: {exc.strerror or exc}")
    report = {
        "file": str(out),
        "from": t0,
        "to": t1,
        "recordings": [str(rec.path) for rec in found],
        "skipped": skipped,
        "messages": counts,
    }
    if as_json:
        print_json(report)
        return
    span = f"{_when(t0)} → {_when(t1)}"
    typer.echo(f"{out}: {sum(counts.values())} records, {span}, {len(found)} recording(s)")
    for topic, n in sorted(counts.items()):
        typer.echo(f"  {topic:<24} {n}")
    for why in skipped:
        typer.echo(f"  skipped: {why}", err=True)


def _when(t: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t))
