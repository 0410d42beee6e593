"""What the emulated `ros2` runs as astiop runs it in process: a verb it has no emulation of
(ros2/verbs/), on the simulator, with the emulated robot's own graph."""

from __future__ import annotations

import shlex

from astiop.robot_programs.emulated_cli.call import Call
from astiop.ros2.validation import validate
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import SAMPLE, BackendError

VERB_TIMEOUT_S = 10.0


class OwnGraph:
    """The simulator as the verbs' transport, with this robot's own graph: its missing names
    left out, /map and ROS 2's own topics in, as `ros2 topic list` prints them here."""

    def __init__(self, robot):
        self._robot = robot

    def __getattr__(self, name: str):
        return getattr(self._robot.backend.verbs, name)

    def graph(self, kind: str) -> list[tuple[str, str]]:
        r = self._robot
        table = {"topic": r.topics, "service": r.services, "action": r.actions}.get(kind)
        return list(table().items()) if table is not None else r.backend.verbs.graph(kind)


def run_verb(robot, call: Call, argv: list[str]) -> int:
    """A verb with no emulation of its own here: run as the simulator in process runs it
    (astiop/ros2/verbs/), printed as ros2 prints it; one ros2 runs until stopped (hz, bw)
    waits for its SIGINT after."""
    checked = validate(shlex.join(["ros2", *argv]), robot.catalog, robot.distro)
    if checked.command is not None and checked.command.name in robot.missing:
        call.wait(3600.0)  # ros2 waits for a topic nobody publishes
    if not checked.valid:
        call.err(checked.reason + "\n")
        return 1
    try:
        text, _ = robot.backend.execute(checked, VERB_TIMEOUT_S, on=OwnGraph(robot))
    except BackendError as exc:
        call.err(f"{exc}\n")
        return 1
    call.out(text)
    if VERBS[checked.command.key].runs_as == SAMPLE:
        call.wait(3600.0)
    return 0
