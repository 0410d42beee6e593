"""The simulator as a transport the verbs run on (ros2/verbs/transport.py): the graph from its
catalog, messages from its state, a publish driving it, its services, its goals, parameters."""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from astiop.ros2.cdr import serialized_size
from astiop.ros2.interfaces import python_repr
from astiop.ros2.printing import indent_yaml, type_of
from astiop.ros2.validation import Checked
from astiop.ros2.verbs.transport import Sample
from astiop.sim.simulator import GoalError
from astiop.transports.base import (
    BackendError,
    command_of,
    interface_of,
    message_of,
    name_of,
)
from astiop.transports.state import yaw_of

if TYPE_CHECKING:
    from astiop.transports.simulator.backend import SimBackend

# a topic's arrivals are followed this long of robot time at most
SAMPLE_S = 5.0


class SimVerbs:
    """The simulator as the transport the verbs run on: its backend's catalog, messages,
    clock, services and parameters (`SimBackend.verbs`)."""

    def __init__(self, backend: SimBackend):
        self.backend = backend
        self.sim = backend.sim

    # -- the graph ----------------------------------------------------------------------
    def graph(self, kind: str) -> list[tuple[str, str]]:
        catalog = self.backend.catalog
        if kind == "node":
            return [(n, "") for n in catalog.nodes]
        if kind == "topic":
            return sorted((n, t.type) for n, t in catalog.topics.items())
        if kind == "service":
            return sorted((n, s.type) for n, s in catalog.services.items())
        return sorted((n, a.type) for n, a in catalog.actions.items())

    def endpoint_counts(self, topic: str) -> tuple[int, int]:
        spec = self.backend.catalog.topics[topic]
        return int(bool(spec.publisher)), int(bool(spec.subscriber))

    def action_servers(self, action: str) -> list[str]:
        return [self.backend.catalog.actions[action].node]

    def node_info(self, node: str) -> dict[str, list[tuple[str, str]]]:
        return self.backend.catalog.node_info(node)

    def interfaces(self) -> list[str]:
        from astiop.ros2.definitions import DEFINITIONS

        return list(DEFINITIONS)

    # -- topics ---------------------------------------------------------------------------
    def take(self, c: Checked, timeout: float) -> dict[str, Any]:
        return self.backend.next_message(name_of(c), timeout)

    def samples(
        self, topic: str, type_: str, enough: Callable[[list[Sample]], bool], timeout: float
    ) -> list[Sample]:
        """Each publication of the topic at its rate, at its instant on the simulator's clock
        (at most SAMPLE_S of robot time, within `timeout` of wall time at real time)."""
        spec = self.backend.catalog.topics[topic]
        if spec.rate_hz == 0 or (topic == "/plan" and self.sim.goal is None):
            raise BackendError(f"{spec.name} is not being published at a rate right now")
        got: list[Sample] = []
        start, deadline = self.sim.t, time.monotonic() + timeout
        while not enough(got) and len(got) / spec.rate_hz <= SAMPLE_S:
            at = start + len(got) / spec.rate_hz
            if at > self.sim.t:
                self.backend.advance(at - self.sim.t, max(0.0, deadline - time.monotonic()))
            got.append((at, serialized_size(type_, self.backend.message(topic))))
        return got

    # -- actuation ----------------------------------------------------------------
    def publish(self, c: Checked, timeout: float) -> tuple[str, Any]:
        cmd = command_of(c)
        twist = message_of(c)
        times = 1 if "once" in cmd.flags else cmd.options["times"]
        rate = cmd.options.get("rate", 1.0)
        lines = ["publisher: beginning loop"]
        job = self.backend.inflight.current("a publish")
        for i in range(times):
            with job.sending():  # the E-STOP ends it between two messages
                self.backend.drive(twist, 0.5 if times == 1 else max(0.5, 1.5 / rate))
            lines.append(f"publishing #{i + 1}: {python_repr('geometry_msgs/msg/Twist', twist)}")
            lines.append("")
            if i + 1 < times:
                self.backend.advance(1.0 / rate, timeout + 1.0 / rate)
        return "\n".join(lines) + "\n", {"published": times, "twist": twist}

    def call(self, c: Checked, timeout: float) -> tuple[str, Any]:
        name, req, type_ = name_of(c), message_of(c), interface_of(c)
        response = self.backend.serve(name, req)
        text = (
            f"requester: making request: {python_repr(type_, req, 0)}\n\n"
            f"response:\n{python_repr(type_, response, 1)}\n\n"
        )
        return text, response

    def send_goal(self, c: Checked, timeout: float) -> tuple[str, Any]:
        goal_msg = message_of(c)
        pose = goal_msg["pose"]["pose"]
        x, y = pose["position"]["x"], pose["position"]["y"]
        th = yaw_of(pose["orientation"])
        lines = [
            "Waiting for an action server to become available...",
            "Sending goal:",
            indent_yaml(goal_msg, 5).rstrip("\n"),
        ]
        try:
            goal = self.sim.goto(x, y, th)
        except GoalError as exc:
            lines += ["Goal was rejected.", ""]
            return "\n".join(lines), {"accepted": False, "reason": str(exc)}
        lines += [f"Goal accepted with ID: {uuid.UUID(int=goal.id).hex}", ""]
        feedback = "feedback" in command_of(c).flags
        start = self.sim.t
        # manual clock: the goal may take minutes of robot time; real time: `timeout` of wall
        limit = 900.0 if not self.backend.realtime else timeout
        wall0 = time.monotonic()
        while self.sim.goal is not None and self.sim.goal.id == goal.id:
            if (not self.backend.realtime and self.sim.t - start > limit) or (
                self.backend.realtime and time.monotonic() - wall0 > limit
            ):
                lines.append(f"Goal still running after {limit:g} s; /stop cancels it")
                return "\n".join(lines) + "\n", {"accepted": True, "status": "RUNNING"}
            self.backend.advance(1.0, timeout)
            if feedback and self.sim.goal is not None:
                s = self.sim.snapshot()
                lines += [
                    "Feedback:",
                    f"    distance_remaining: {s.distance_remaining:.3f}",
                    f"    navigation_time: {self.sim.t - start:.1f} s",
                    "",
                ]
        result = self.sim.last_result
        ok = result is not None and result.id == goal.id and result.status == "succeeded"
        status = (
            "SUCCEEDED"
            if ok
            else ("CANCELED" if result and result.status == "canceled" else "ABORTED")
        )
        why = result.message if result is not None else "the goal ended without a result"
        res = {"error_code": 0 if ok else 1, "error_msg": "" if ok else why}
        lines += [
            "Result:",
            indent_yaml(res).rstrip("\n"),
            "",
            f"Goal finished with status: {status}",
        ]
        px, py, pth = self.sim.pose
        return "\n".join(lines) + "\n", {
            "accepted": True,
            "status": status,
            "result": res,
            "final_pose": {"x": px, "y": py, "theta": pth},
        }

    # -- parameters ---------------------------------------------------------------------
    def list_params(self, node: str | None, timeout: float) -> list[tuple[str, str, str]]:
        return [(n, name, type_of(value)) for (n, name), value in self.backend.params.items()]

    def get_param(self, node: str, name: str, timeout: float) -> Any:
        return self.backend.params[(node, name)]

    def set_param(self, node: str, name: str, value: Any, timeout: float) -> str:
        self.backend.params[(node, name)] = value
        if name == "max_linear_speed":
            self.sim.gains = type(self.sim.gains)(v_max=value, w_max=self.sim.gains.w_max)
        return ""
