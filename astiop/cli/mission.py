"""`astiop mission`: list, show, pause, resume and cancel the robot's missions (multi-step
work)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import typer

from astiop.cli.common import Ending, fail, print_json, state, take_control
from astiop.cli.mission_follow import follow_mission

app = typer.Typer(help="List, show, pause, resume and cancel missions.", no_args_is_help=True)
ID_MAX = 2**63 - 1  # SQLite's INTEGER: a larger id is refused in one line, not by the database


def _mission_id() -> int:
    return typer.Argument(..., min=1, max=ID_MAX, help="The mission's id (astiop mission list).")


def _one(ctx: typer.Context, mission_id: int) -> dict:
    from astiop.missions import view

    m = view.as_json(state(ctx).store, mission_id)
    if m is None:
        fail(f"no mission {mission_id} (astiop mission list shows them)")
    return m


@app.command("list")
def list_missions(
    ctx: typer.Context,
    limit: int = typer.Option(20, "--limit", "-n", min=1, max=1000),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """The latest missions, newest first."""
    from astiop.missions import view

    store = state(ctx).store
    missions = [view.as_json(store, row["id"]) for row in store.missions(limit)]
    if as_json:
        print_json(missions)
        return
    if not missions:
        typer.echo("no missions")
    for m in missions:
        typer.echo(view.summary(m))


@app.command("show")
def show(
    ctx: typer.Context,
    mission_id: int = _mission_id(),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """One mission: each step, how it ended and where the robot was."""
    from astiop.missions import view

    m = _one(ctx, mission_id)
    if as_json:
        print_json(m)
        return
    typer.echo(view.summary(m))
    typer.echo(view.escape_controls(f"request: {m['request']}"))
    for line in view.step_lines(m):
        typer.echo(f"  {line}")


@app.command("cancel")
def cancel(
    ctx: typer.Context,
    mission_id: int = _mission_id(),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Cancel a running or paused mission (its process stops the robot) or drop an
    interrupted one."""
    m = _one(ctx, mission_id)
    before = state(ctx).store.request_mission_cancel(mission_id)
    if before not in ("running", "paused", "interrupted", "queued"):
        fail(f"mission {mission_id} is {m['status']}: nothing to cancel")
    said = "cancel asked of its process" if before in ("running", "paused") else "dropped"
    if as_json:
        print_json({"id": mission_id, "was": before, "now": said})
    else:
        typer.echo(f"mission {mission_id}: {said}")


@app.command("pause")
def pause(
    ctx: typer.Context,
    mission_id: int = _mission_id(),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Hold a running mission at the end of its current step (that step ends as the robot
    reports it; the next starts only on `astiop mission resume`)."""
    m = _one(ctx, mission_id)
    if m["status"] == "paused" or m["pause_requested"]:
        fail(f"mission {mission_id} is paused already (astiop mission resume {mission_id})")
    before = state(ctx).store.request_mission_pause(mission_id)
    if before != "running":
        fail(f"mission {mission_id} is {m['status']}: only a running mission pauses")
    said = f"pauses at the end of step {m['step']} of {m['steps_total']}"
    if as_json:
        print_json({"id": mission_id, "was": before, "now": said})
    else:
        typer.echo(f"mission {mission_id}: {said}")


@app.command("resume")
def resume(
    ctx: typer.Context,
    mission_id: int = _mission_id(),
    from_step: int = typer.Option(
        None, "--from", min=1, max=10_000, help="Step to resume from (default: the one it was on)."
    ),
    yes: bool = typer.Option(False, "--yes", "-y", help="Do not ask before moving the robot."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Go on with a mission. A paused one: its own process goes on with the next step (no
    --from). An interrupted one (its process ended): this process drives it from the step it
    was on, or --from, and waits for it to end."""
    from astiop.cli.common import interactive
    from astiop.missions import view
    from astiop.missions.runner import MissionError, MissionRunner
    from astiop.robot.factory import make_robot_gateway
    from astiop.transports.base import BackendError

    st = state(ctx)
    m = _one(ctx, mission_id)
    if m["status"] == "paused" or m["pause_requested"]:
        _unpause(st, m, from_step, as_json)
        return
    if m["status"] not in ("interrupted", "queued"):
        fail(f"mission {mission_id} is {m['status']}, not paused or interrupted: nothing to resume")
    start = m["step"] if from_step is None else from_step
    if not 1 <= start <= m["steps_total"]:
        fail(f"--from must be a step of mission {mission_id}: 1 to {m['steps_total']}")
    rest = "; ".join(s["label"] for s in m["steps"][start - 1 :])
    if not yes:
        if not interactive():
            fail("resuming moves the robot: confirm it with --yes")
        if not typer.confirm(f"resume mission {mission_id} from step {start}: {rest}?", err=True):
            fail("not confirmed: nothing was sent to the robot")
    try:
        gateway = make_robot_gateway(st.settings, st.store)
    except BackendError as exc:
        fail(str(exc))
    take_control(gateway, st)

    def on_step(report) -> None:
        if not as_json:
            typer.echo(report.line(), err=True)

    def on_note(text: str) -> None:
        if not as_json:
            typer.echo(text, err=True)

    runner = MissionRunner(gateway, st.store, on_step=on_step, on_note=on_note)
    gateway.start()
    try:
        runner.resume(mission_id, start)
    except MissionError as exc:
        gateway.close()
        fail(str(exc))
    ending = follow_mission(runner, mission_id)
    gateway.close()
    if as_json:
        print_json(view.as_json(st.store, mission_id))
    else:
        typer.echo(ending)
    Ending.at_once = st.settings.robot.backend != "ros2"
    final = st.store.mission(mission_id) or {}
    if final.get("status") != "succeeded":
        raise typer.Exit(1)


def _unpause(st, m: dict, from_step: int | None, as_json: bool) -> None:
    """A paused mission goes on in the process that drives it (asked through the store)."""
    if from_step is not None:
        fail("--from resumes an interrupted mission only; a paused one goes on where it holds")
    before = st.store.request_mission_pause(m["id"], pause=False)
    if before not in ("running", "paused"):
        fail(f"mission {m['id']} is {before}: nothing to resume")
    said = "resume asked of its process" if before == "paused" else "the pause was withdrawn"
    if as_json:
        print_json({"id": m["id"], "was": before, "now": said})
    else:
        typer.echo(f"mission {m['id']}: {said}")


def drive_detached(st, mission_id: int) -> Path:
    """`astiop chat --no-wait`: a process of its own drives the queued mission (`mission
    resume`), on the same database and robot, after this one has ended; its output goes to a
    log file beside the database."""
    robot = st.settings.robot
    log = Path(st.db_path).parent / "logs" / f"mission-{mission_id}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    argv = [sys.executable, "-m", "astiop", "--db", str(st.db_path), "--robot", robot.backend]
    argv += ["--ros2-transport", robot.ros2_transport, "mission", "resume", str(mission_id)]
    with open(log, "ab") as out:
        subprocess.Popen(
            [*argv, "--yes"],
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # not ended with this process's terminal
        )
    return log
