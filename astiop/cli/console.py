"""Opening the Textual console from the CLI."""

from __future__ import annotations

import contextlib
import gc
import os
import threading
from pathlib import Path

import typer

from astiop.cli.common import CliState
from astiop.native_stdout import native_output_to_stderr
from astiop.robot.fleet import is_fleet

# `astiop serve`'s warm console: its services built (nothing running yet), waits for a tab
SPARE = "ASTIOP_CONSOLE_SPARE"
QUICK_S = 0.25  # a console opens once the fleet's graph showed no new robot for this long


def _wait_for_tab() -> None:
    """Block until `astiop serve` hands this console a tab: one line, "go WIDTH HEIGHT", read
    byte by byte from stdin (what follows is the web driver's, not ours). EOF: not needed."""
    line = b""
    while not line.endswith(b"\n"):
        byte = os.read(0, 1)
        if not byte:
            raise SystemExit(0)
        line += byte
        if len(line) > 64:
            raise SystemExit("astiop: a spare console got something else than its tab")
    words = line.decode("ascii", "replace").split()
    if len(words) == 3 and words[0] == "go" and words[1].isdigit() and words[2].isdigit():
        os.environ["COLUMNS"], os.environ["ROWS"] = words[1], words[2]


def _join_the_graph_early(settings) -> None:
    """A console on a ROS 2 robot through rclpy: the process's participant started while the
    console's modules load, so discovery (seconds on a large fleet) begins at once."""
    from astiop.robot.factory import ros2_transport

    if settings.robot.backend != "ros2" or ros2_transport(settings)[0] != "rclpy":
        return

    def start() -> None:
        from astiop.transports.rclpy.node import ros_process

        with contextlib.suppress(Exception):  # said by the robot's gateway, made next
            ros_process()

    threading.Thread(target=start, name="ros2-early", daemon=True).start()


def run_console(st: CliState, record: str | None = None) -> None:
    spare = os.environ.pop(SPARE, None) == "1"  # first: ASTIOP_* names settings
    native_output_to_stderr()  # first: a served console's stdout is its tab's stream
    _join_the_graph_early(st.fleet_settings)
    from astiop.agent.models.specs import SpecError
    from astiop.app import make_app
    from astiop.cli.common import fail
    from astiop.recording import default_path
    from astiop.transports.base import BackendError

    record_path = None
    if record is not None:
        record_path = Path(record).expanduser() if record else default_path(st.db_path.parent)
    settings, fleet = st.settings, None
    if is_fleet(st.fleet_settings):
        settings, fleet = open_fleet(st, keep_finding=True)
    try:
        app = make_app(settings, st.store, record=record_path, fleet=fleet)
    except (SpecError, BackendError) as exc:
        if fleet is not None:
            fleet.close()
        fail(str(exc))
    if fleet is not None:  # every robot's gateway opened while the screen starts
        fleet.start()
    if spare:  # built ahead (a ROS 2 robot discovered, the model loading): now its tab
        _wait_for_tab()
    # what start-up made lives as long as the process: kept out of the collector's full scans,
    # which a planner's allocations trigger (in-process simulator: 0.97 → 0.69 ms a plan)
    gc.freeze()
    from astiop.widgets import camera_pixels

    # asked of the terminal before Textual reads it
    app.camera_pixels = camera_pixels.detect(settings.console.camera)
    app.run()


def open_fleet(st: CliState, who: str = "console", keep_finding: bool = False):
    """The fleet's robots found (said as they are), the current one's settings (--robot-name,
    else the first), and a watch of every one of them (not started). `keep_finding`: the
    console opens on the robots found first (the graph quiet for QUICK_S) and the watch adds
    those found later, as they are."""
    from functools import partial

    from astiop.cli.common import fail
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import FleetError, FleetFinder, find_robots, robot_settings
    from astiop.robot.fleet_watch import FleetWatch

    whole = st.fleet_settings
    typer.echo("finding the fleet's robots…", err=True)

    def said(robot) -> None:
        typer.echo(f"  {robot.name} ({robot.namespace})", err=True)

    def opener(robot):
        return (robot.name, robot.namespace,
                partial(make_robot_gateway, robot_settings(whole, robot.name), st.store,
                        realtime=True, who=who, discover=False))  # fmt: skip

    finder = None
    try:
        if keep_finding and whole.fleet.discover == "auto":
            finder = FleetFinder(whole)
            robots = finder.settle(said, QUICK_S, wanted=st.robot_name)
        else:
            robots = find_robots(whole, said)
    except FleetError as exc:
        if finder is not None:
            finder.close()
        fail(str(exc))
    current = st.robot_name or robots[0].name
    if current not in {r.name for r in robots}:
        if finder is not None:
            finder.close()
        fail(f"no robot named '{current}' in the fleet (its robots: "
             f"{', '.join(r.name for r in robots)})")  # fmt: skip
    watch = FleetWatch([opener(r) for r in robots])
    watch.settings_for = partial(robot_settings, whole)
    if finder is not None:
        watch.find_more = lambda: [opener(r) for r in finder.poll()]
        watch.stop_finding = finder.close
    return robot_settings(whole, current), watch
