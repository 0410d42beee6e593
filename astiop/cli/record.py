"""`astiop record`: the robot's topics, events and the agent's turns into an MCAP file."""

from __future__ import annotations

import contextlib
import math
import time
from pathlib import Path

import typer

from astiop.cli.common import fail, print_json, state


def record(
    ctx: typer.Context,
    file: Path | None = typer.Argument(
        None, help="The MCAP file (default: <data dir>/sessions/<timestamp>.mcap)."
    ),
    duration: float | None = typer.Option(
        None, "--duration", help="Seconds to record (default 10; with --goto, until it ends)."
    ),
    goto: list[str] = typer.Option(
        [],
        "--goto",
        help="Drive to this named location while recording (it is the consent); repeat for a tour.",
    ),
    scan_hz: float | None = typer.Option(None, "--scan-hz", help="Decimate /scan to this rate."),
    repair: bool = typer.Option(
        False, "--repair", help="Recover what a cut-off FILE holds into FILE.repaired.mcap."
    ),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Record a session headless, on the simulator (real time) or the robot."""
    from astiop.recording import RecordingError, SessionRecorder, default_path, summary
    from astiop.recording import repair as repair_file

    if repair:
        if file is None or not file.is_file():
            fail("--repair needs the FILE of a recording")
        out = file.with_suffix(".repaired.mcap")
        try:
            counts = repair_file(file, out)
        except (RecordingError, OSError) as exc:
            fail(str(exc))
        _report(out, counts, as_json)
        return
    for name, value in (("--duration", duration), ("--scan-hz", scan_hz)):
        if value is not None and not (math.isfinite(value) and 0 < value <= 86400):
            fail(f"{name} must be a positive number")
    from astiop.cli.console import open_fleet
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import is_fleet
    from astiop.transports.base import BackendError

    st = state(ctx)
    path = file or default_path(st.db_path.parent)
    for name in goto:
        st.store.require_location(name)  # a one-line error before anything starts
    settings, fleet = st.settings, None
    if is_fleet(st.fleet_settings):  # every robot recorded; --goto drives the current one
        settings, fleet = open_fleet(st, who="astiop record")
    try:
        gateway = make_robot_gateway(
            settings, st.store, realtime=True, who="astiop record", discover=fleet is None
        )
        gateway.start()
    except BackendError as exc:
        if fleet is not None:
            fleet.close()
        fail(str(exc))
    if fleet is not None:
        current = next(n for n, ns, _ in fleet.robots if ns == settings.robot.namespace)
        fleet.adopt(current, gateway)
        fleet.start()
    try:
        recorder = SessionRecorder(
            path,
            gateway,
            st.store,
            scan_hz=scan_hz,
            fleet=fleet.names if fleet else None,
            gateway_of=fleet.gateway_of if fleet else None,
        ).start()
    except RecordingError as exc:
        _close(gateway, fleet)
        fail(str(exc))
    t0 = time.monotonic()
    limit = duration if duration is not None else (600.0 * len(goto) if goto else 10.0)
    outcomes: list[str] = []
    seq = gateway.state().event_seq

    def progress() -> None:
        nonlocal seq
        events = gateway.events_since(seq)  # the gateway keeps each in the store
        if events:
            seq = max(seq, events[-1].seq)
        if not as_json:
            typer.echo(f"\r  recording {time.monotonic() - t0:5.1f} s", nl=False, err=True)

    try:
        for name in goto:
            if time.monotonic() - t0 >= limit:
                break
            loc = st.store.get_location(name)
            target = (loc.x, loc.y) if loc else None
            outcome = _drive_to(gateway, name, t0 + limit, progress, target)
            outcomes.append(f"goal {name}: {outcome}")
        while not goto and time.monotonic() - t0 < limit:
            time.sleep(0.2)
            progress()
    except KeyboardInterrupt:
        pass
    except RecordingError as exc:
        with contextlib.suppress(RecordingError):
            recorder.stop()
        _close(gateway, fleet)
        fail(str(exc))
    progress()
    try:
        counts = recorder.stop()
    except RecordingError as exc:
        _close(gateway, fleet)
        fail(str(exc))
    _close(gateway, fleet)
    if not as_json:
        typer.echo("", err=True)
        for line in outcomes:
            typer.echo(line)
    _report(path, summary(path) if counts else counts, as_json)


def _close(gateway, fleet) -> None:
    if fleet is not None:
        fleet.close()  # the current robot's gateway with the others
    else:
        gateway.close()


def _drive_to(gateway, name: str, deadline: float, progress, target) -> str:
    """Start a goal to a named location and wait (until the deadline) for how it ended; a
    robot that reports no outcome is judged by its reported pose (as the agent does)."""
    from astiop.agent.goals import outcome_at
    from astiop.recording import RecordingError
    from astiop.ros2.render import goto_command

    result = gateway.run(goto_command(name), confirm=lambda _c: True, source="record")
    if not result.executed or result.error:
        raise RecordingError(f"--goto {name}: {result.reason or result.error}")
    time.sleep(0.5)  # the goal shows in the robot's status
    while time.monotonic() < deadline:
        outcome = gateway.wait_until_idle(min(1.0, deadline - time.monotonic()))
        progress()
        if outcome is not None:
            return outcome
        if gateway.state().state_word not in ("navigating", "docking", "blocked"):
            return outcome_at(gateway, target, name)
    return "still going when the recording ended"


def _report(path: Path, counts: dict[str, int], as_json: bool) -> None:
    if as_json:
        print_json({"file": str(path), "messages": counts})
        return
    typer.echo(f"{path}: {sum(counts.values())} messages")
    for topic, n in sorted(counts.items()):
        typer.echo(f"  {topic:<24} {n}")
