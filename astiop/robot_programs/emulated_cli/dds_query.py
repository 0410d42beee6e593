"""The graph as the emulated `ros2`'s node discovers it over DDS, and a verb with no emulation
of its own there that only reads the graph (topic find): run as astiop runs it in process
(ros2/verbs/), on that graph."""

from __future__ import annotations

import shlex
from typing import Any

from astiop.robot_programs.emulated_cli.call import Call
from astiop.ros2.grammar import parse
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.transports.rclpy.graph import full_name, hidden

Pairs = list[tuple[str, list[str]]]  # (name, its types), as rclpy's graph API gives them


class DdsGraph:
    """One rclpy node's view of the graph: names and types as the `ros2 ... list` verbs list
    them, hidden ones (a part that starts with "_") left out unless asked for."""

    def __init__(self, node: Any):
        self.node = node

    def topics(self, include_hidden: bool | None) -> Pairs:
        pairs = self.node.get_topic_names_and_types()
        return [(n, list(t)) for n, t in pairs if include_hidden or not hidden(n)]

    def services(self, include_hidden: bool | None) -> Pairs:
        pairs = self.node.get_service_names_and_types()
        return [(n, list(t)) for n, t in pairs if include_hidden or not hidden(n)]

    def nodes(self, include_hidden: bool | None) -> list[str]:
        return sorted(
            full_name(ns, n) for n, ns in self.node.get_node_names_and_namespaces()
            if include_hidden or not n.startswith("_")
        )  # fmt: skip

    def graph(self, kind: str) -> list[tuple[str, str]]:
        """The verbs' Transport primitive: (name, types) of one kind, hidden ones left out."""
        if kind == "node":
            return [(n, "") for n in self.nodes(False)]
        read = {"topic": self.topics, "service": self.services}.get(kind)
        if read is None:
            raise RuntimeError(f"the emulated ros2 over DDS does not list {kind}s for a verb")
        return [(n, ", ".join(t)) for n, t in read(False)]


def run_query(graph: DdsGraph, distro: str, call: Call, a: dict, argv: list[str]) -> int:
    """A verb that only reads the graph, with no emulation of its own here (topic find): run
    as astiop runs it in process (ros2/verbs/), on this node's view of the graph; argv, not
    the parsed `a`, is what it parses."""
    cmd = parse(shlex.join(["ros2", *argv]), distro)
    text, _ = VERBS[cmd.key].run(graph, Checked(cmd.text, cmd, True), 10.0)
    call.out(text)
    return 0
