"""`astiop estop`: stop the robot from a second shell or a script, the robot first, then its
graph, then the database; `--release` names who pressed; a keeper holds a press on the graph."""

from __future__ import annotations

import typer

from astiop.cli.common import Ending, fail, interactive, state


def estop(
    ctx: typer.Context,
    release: bool = typer.Option(
        False, "--release", help="Release the E-STOP (asks first; --yes does not ask)."
    ),
    yes: bool = typer.Option(False, "--yes", "-y", help="Release without asking."),
    hold: float = typer.Option(0.0, "--hold", hidden=True, help="Keep a press on the graph."),
    pressed_by: int = typer.Option(0, "--pressed-by", hidden=True),
    every: bool = typer.Option(
        False,
        "--all",
        help="Every robot of the fleet at once ([[fleet.robots]], or with --fleet auto every "
        "robot namespace on the domain, read first).",
    ),
) -> None:
    """E-STOP from a second shell or a script: stop the robot on the configured backend and
    latch it in the database, as the console's ctrl+e does; every astiop process on that
    database then refuses motion until it is released. --robot-name NAME stops one robot of
    the fleet, --all every one."""
    from astiop.robot.estop_latch import HELD_FOR_ALL

    st = state(ctx)
    if hold:
        from astiop.robot.factory import leave_the_graph

        try:
            _hold(st, hold, pressed_by)
        finally:  # its word said and closed: no interpreter teardown of rclpy's threads after
            leave_the_graph(LEAVE_S)
            Ending.at_once = True
        return
    if every and st.robot_name is not None:
        fail("--all stops every robot of the fleet: leave out --robot-name")
    if every and not release:
        from astiop.cli.fleet import estop_all

        estop_all(st)
        return
    if release and every:
        from astiop.cli.fleet import release_all

        release_all(st, yes)
        return
    ns = st.settings.robot.namespace  # a namespaced robot latches its own E-STOP
    if release and ns and st.robot_name is not None and st.store.estop_latch() is not None:
        fail(HELD_FOR_ALL.replace("still holds it", f"holds {st.robot_name}"))
    if release:
        _release(st, ns, yes)
        return
    _press(st, ns)


def _release(st, ns: str, yes: bool) -> None:
    """`astiop estop --release`: a person's, knowing what they release (on a live robot, who
    pressed it, where and when, as every station says it on the robot's graph)."""
    own = bool(ns) and st.store.robot_latch(ns) is not None
    latch = st.store.estop_latch() if st.robot_name is None else None
    latch = latch or (st.store.robot_latch(ns) if ns else None)
    live = st.settings.robot.backend == "ros2"  # its own stop may hold it (a bare /stop)
    gateway = _release_gateway(st) if live else None
    try:
        pressed = gateway.pressed_by() if gateway is not None else None
        if latch is None and pressed is None and not live:
            typer.echo("the E-STOP is not engaged")
            return
        what = f"the E-STOP pressed by {pressed.words}" if pressed else "the E-STOP"
        if not yes:
            if not interactive():
                fail("releasing the E-STOP needs a person to confirm it (or --yes)")
            if not typer.confirm(f"release {what} (the robot may move again)?", err=True):
                fail("not released", code=1)
        if gateway is None:
            if st.robot_name is None:
                st.store.release_estop("estop --release")
            if own:
                st.store.release_robot(ns, "estop --release")
        else:
            has_release = gateway.serves("/release", st.settings.robot.ros2_timeout_s)
            failed = gateway.release_estop(pressed)
            if failed:
                fail("; ".join(failed), code=1)
        if latch is not None or pressed is not None:
            named = f" ({st.robot_name})" if st.robot_name else ""
            by = f" (pressed by {pressed.words})" if pressed else ""
            typer.echo(f"E-STOP released{named}{by}")
        else:
            typer.echo("the E-STOP is not latched in the database")
        if gateway is not None and has_release:
            typer.echo("the robot's own stop released (/release)")
    finally:
        if gateway is not None:
            gateway.close()


def _release_gateway(st):
    """The live robot's door, its graph read, for a release (a robot that latches its own
    stop, a /release service on its graph, is released too)."""
    from astiop.robot.factory import make_robot_gateway
    from astiop.transports.base import BackendError

    try:
        return make_robot_gateway(st.settings, st.store, who="estop --release", restore_latch=False)
    except BackendError as exc:
        fail(f"the robot was not reached to release its own stop: {exc}", code=1)


LEAVE_S = 2.0  # the rclpy close before exit: longer, and the exit goes on without it
ROBOT_GONE_S = 60.0  # a keeper whose robot left the graph this long has nothing to hold


def keep_on_the_graph(st, at: float, robot_name: str | None = None) -> None:
    """This process's press outlives it: a keeper (`astiop estop --hold`, in a session of its
    own) says it on the robot's graph, holds the robot's lock input, and stops the robot again
    whenever it comes back to the graph, until it is released. `robot_name`: one of a fleet."""
    import os
    import subprocess
    import sys

    from astiop.cli import global_args

    if not st.settings.robot.estop_keeper:
        return
    named = ["--robot-name", robot_name] if robot_name else []
    argv = [sys.executable, "-m", "astiop", *global_args(), *named, "estop", "--hold", repr(at)]
    argv += ["--pressed-by", str(os.getpid())]
    try:
        keeper = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,  # the shell that ran `astiop estop` may close
        )
    except OSError as exc:
        typer.echo(f"astiop: no keeper of the E-STOP on the robot's graph: {exc}", err=True)
        return
    robot = f"{robot_name}'s" if robot_name else "the robot's"
    typer.echo(f"held on {robot} graph until released (keeper pid {keeper.pid})", err=True)


def _hold(st, at: float, by: int) -> None:
    """`astiop estop --hold AT`: keep saying the robot's E-STOP pressed at AT (by the `astiop
    estop` that started this) on its graph, and its lock input true, until someone releases it,
    or the robot is gone from the graph."""
    import time

    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.station_latch import OPENED_S, Act
    from astiop.transports.base import BackendError

    store, _why = store_softly(st)
    try:
        gateway = make_robot_gateway(
            st.settings, store, who="estop (keeper)", discover=False, restore_latch=False
        )
    except BackendError as exc:
        fail(str(exc), code=1)
    graph = gateway.station_latch
    try:
        if graph is None:
            return
        # held from its first word, said as its channel opens: a release said while it settles
        # then waits for this keeper to say it back
        graph.pressed(Act(at, "estop", Act.here("").host, by))
        if not graph.wait_ready(OPENED_S) or not graph.on_graph:  # opened, then settled
            return
        seen, there = time.monotonic(), gateway.backend.robot_present()
        while graph.engaged:
            gateway.follow_latch()  # holds this process's robot (its lock input) as latched
            present = gateway.backend.robot_present()
            if present and not there:  # back on the graph (a hung node resumed): stopped now
                gateway.backend.estop()
            there = present
            if present is not False:
                seen = time.monotonic()
            elif time.monotonic() - seen > ROBOT_GONE_S:
                return
            time.sleep(0.2)
    finally:
        gateway.close()


def store_softly(st):
    """The database, or why it cannot be had: an E-STOP is never held up by its record."""
    from astiop.store import Store, StoreError

    try:
        return Store(st.db_path), ""
    except (StoreError, OSError) as exc:
        return None, str(exc)


def _record_press(store, ns: str, at: float) -> str:
    """The press latched in the database after the robot was told; what went wrong ("")."""
    try:
        latched = store.latch_robot(ns, "estop", at) if ns else store.latch_estop("estop", at)
    except Exception as exc:  # noqa: BLE001 - full, damaged, locked, read-only
        return f"not latched in the database: {exc}"
    return "" if latched else "released meanwhile: a release made after this press stands"


def _press(st, ns: str) -> None:
    """`astiop estop`: the robot told first, then the robot's graph, then the database; a
    database that cannot be written never delays nor prevents the stop."""
    from astiop import estop_sql
    from astiop.robot.factory import leave_the_graph, make_robot_gateway
    from astiop.transports.base import BackendError

    at = estop_sql.pressed_at()  # every step of this press is this one press
    try:
        gateway = make_robot_gateway(
            st.settings, None, who="estop", discover=False, restore_latch=False
        )
    except BackendError as exc:
        store, why = store_softly(st)
        said = _record_press(store, ns, at) if store is not None else why
        held = "E-STOP not latched anywhere" if said else "E-STOP latched in the database"
        fail(f"{held}, and the robot was not reached: {exc}", code=1)
    failures = gateway.estop(at)
    if gateway.station_latch is not None:  # said on the graph from now until released
        keep_on_the_graph(st, at)
    store, why = store_softly(st)
    recorded = (
        _record_press(store, ns, at) if store is not None else f"not latched in the database: {why}"
    )
    # the zero-Twist burst and /stop go out before this process exits
    failures += gateway.settle_estop(st.settings.robot.ros2_timeout_s)
    pressed = gateway.station_latch
    released = pressed is not None and pressed.press is not None and not pressed.engaged
    on_graph = pressed is not None and pressed.on_graph
    gateway.close()
    # all said and sent: its peers told it left (bounded), then no interpreter teardown (rclpy's,
    # DDS's threads) between the stop and the shell that waits for it
    leave_the_graph(LEAVE_S)
    Ending.at_once = True
    for failure in failures:
        typer.echo(f"astiop: {failure}", err=True)
    if released and pressed is not None and pressed.release is not None:
        typer.echo(f"E-STOP engaged, then released by {pressed.release.words}")
        return
    if recorded.startswith("released meanwhile"):
        typer.echo(f"E-STOP engaged, then {recorded}")
        return
    if recorded:
        typer.echo(f"astiop: {recorded}", err=True)
        held = "said on the robot's graph" if on_graph else "held nowhere else"
        typer.echo(f"E-STOP engaged; {held} (the database was not written)")
        raise typer.Exit(1)
    typer.echo("E-STOP engaged and latched" + (" (with failures above)" if failures else ""))
    if failures:
        raise typer.Exit(1)
