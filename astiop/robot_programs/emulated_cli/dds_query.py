"""A verb the emulated `ros2` over DDS has no emulation of, that only reads the graph (topic
find): run as astiop runs it in process (ros2/verbs/), on the graph this node discovers."""

from __future__ import annotations

import shlex

from astiop.robot_programs.emulated_cli.call import Call
from astiop.ros2.grammar import parse
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS


class DdsGraph:
    """The graph as this node discovers it, for a verb that reads nothing else."""

    def __init__(self, ros2):
        self._ros2 = ros2

    def graph(self, kind: str) -> list[tuple[str, str]]:
        if kind == "node":
            return [(n, "") for n in self._ros2._nodes(False)]
        read = {"topic": self._ros2._topics, "service": self._ros2._services}.get(kind)
        if read is None:
            raise RuntimeError(f"the emulated ros2 over DDS does not list {kind}s for a verb")
        return [(n, ", ".join(t)) for n, t in read(False)]


def run_query(ros2, call: Call, a: dict, argv: list[str]) -> int:
    """A verb that only reads the graph, with no emulation of its own here (topic find): run
    as astiop runs it in process (ros2/verbs/), on this node's view of the graph."""
    cmd = parse(shlex.join(["ros2", *argv]), ros2.distro)
    text, _ = VERBS[cmd.key].run(DdsGraph(ros2), Checked(cmd.text, cmd, True), 10.0)
    call.out(text)
    return 0
