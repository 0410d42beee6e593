"""What the in-process transports (the simulator, rclpy) give a verb to run on: the graph, one
message, a topic's arrivals, a publish, a service call, a goal, parameters. A transport that
cannot do one raises BackendError saying so."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from astiop.ros2.verbs.base import Output

Sample = tuple[float, int]  # (received at, s on the transport's clock; serialized bytes)


class Transport(Protocol):
    def graph(self, kind: str) -> list[tuple[str, str]]:
        """(name, type) of every topic, service or action; (name, "") of every node."""

    def endpoint_counts(self, topic: str) -> tuple[int, int]:
        """(publishers, subscribers) of a topic."""

    def action_servers(self, action: str) -> list[str]: ...

    def node_info(self, node: str) -> dict[str, list[tuple[str, str]]]: ...

    def interfaces(self) -> list[str]: ...

    def take(self, checked: Any, timeout: float) -> dict[str, Any]:
        """The next message on the command's topic (its latest, where that is the next)."""

    def samples(
        self, topic: str, type_: str, enough: Callable[[list[Sample]], bool], timeout: float
    ) -> list[Sample]:
        """The arrivals on a topic until `enough` of them came (or `timeout` passed)."""

    def publish(self, checked: Any, timeout: float) -> Output: ...

    def call(self, checked: Any, timeout: float) -> Output: ...

    def send_goal(self, checked: Any, timeout: float) -> Output: ...

    def list_params(self, node: str | None, timeout: float) -> list[tuple[str, str, str]]:
        """(node, name, type word) of each parameter of one node, or of every node."""

    def get_param(self, node: str, name: str, timeout: float) -> Any: ...

    def set_param(self, node: str, name: str, value: Any, timeout: float) -> str:
        """The reason the node gave, if any; BackendError if it refused."""
