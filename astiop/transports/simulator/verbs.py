"""The simulator as a transport the verbs run on (ros2/verbs/transport.py): the graph from its
catalog, messages from its state, a publish driving it, its services, its goals, parameters."""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable
from typing import Any

from astiop.ros2.cdr import serialized_size
from astiop.ros2.interfaces import python_repr
from astiop.ros2.printing import indent_yaml, type_of
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.sim.simulator import GoalError
from astiop.store import LocationError
from astiop.transports.base import BackendError
from astiop.transports.state import yaw_of

# a topic's arrivals are followed this long of robot time at most
SAMPLE_S = 5.0


class SimVerbs:
    """Mixed into SimBackend: uses its sim, store, catalog, params and topic messages."""

    def execute(self, checked: Checked, timeout: float = 10.0, on: Any = None) -> tuple[str, Any]:
        """`on`: what the verb runs on, if not this simulator alone (a robot program's view)."""
        cmd = checked.command
        if checked.kind == "actuate" and self.sim.e_stopped and cmd.name != "/stop":
            raise BackendError("the E-STOP is engaged: nothing was sent")
        try:
            with self.actuating(checked):  # refused while the E-STOP holds, ended by it
                return VERBS[cmd.key].run(on or self, checked, timeout)
        except (GoalError, LocationError) as exc:
            raise BackendError(str(exc)) from None
        except BackendError:
            raise
        except Exception as exc:  # the simulator must never take the caller down
            raise BackendError(f"the simulator failed: {type(exc).__name__}: {exc}") from None

    # -- the graph ----------------------------------------------------------------------
    def graph(self, kind: str) -> list[tuple[str, str]]:
        if kind == "node":
            return [(n, "") for n in self.catalog.nodes]
        entries = {"topic": self.catalog.topics, "service": self.catalog.services}.get(
            kind, self.catalog.actions
        )
        return sorted((n, e.type) for n, e in entries.items())

    def endpoint_counts(self, topic: str) -> tuple[int, int]:
        spec = self.catalog.topics[topic]
        return int(bool(spec.publisher)), int(bool(spec.subscriber))

    def action_servers(self, action: str) -> list[str]:
        return [self.catalog.actions[action].node]

    def node_info(self, node: str) -> dict:
        return self.catalog.node_info(node)

    def interfaces(self) -> list[str]:
        from astiop.ros2.definitions import DEFINITIONS

        return list(DEFINITIONS)

    # -- topics ---------------------------------------------------------------------------
    def take(self, c: Checked, timeout: float) -> dict[str, Any]:
        return self._wait_for_message(c.command.name, timeout)

    def samples(
        self, topic: str, type_: str, enough: Callable[[list], bool], timeout: float
    ) -> list[tuple[float, int]]:
        """Each publication of the topic at its rate, at its instant on the simulator's clock
        (at most SAMPLE_S of robot time, within `timeout` of wall time at real time)."""
        spec = self.catalog.topics[topic]
        if spec.rate_hz == 0 or (topic == "/plan" and self.sim.goal is None):
            raise BackendError(f"{spec.name} is not being published at a rate right now")
        got: list[tuple[float, int]] = []
        start, deadline = self.sim.t, time.monotonic() + timeout
        while not enough(got) and len(got) / spec.rate_hz <= SAMPLE_S:
            at = start + len(got) / spec.rate_hz
            if at > self.sim.t:
                self.advance(at - self.sim.t, max(0.0, deadline - time.monotonic()))
            got.append((at, serialized_size(type_, self.message(topic))))
        return got

    # -- actuation ----------------------------------------------------------------
    def publish(self, c: Checked, timeout: float) -> tuple[str, Any]:
        cmd = c.command
        twist = c.message
        times = 1 if "once" in cmd.flags else cmd.options["times"]
        rate = cmd.options.get("rate", 1.0)
        lines = ["publisher: beginning loop"]
        job = self.inflight.current("a publish")
        for i in range(times):
            with job.sending():  # the E-STOP ends it between two messages
                self.drive(twist, 0.5 if times == 1 else max(0.5, 1.5 / rate))
            lines.append(f"publishing #{i + 1}: {python_repr('geometry_msgs/msg/Twist', twist)}")
            lines.append("")
            if i + 1 < times:
                self.advance(1.0 / rate, timeout + 1.0 / rate)
        return "\n".join(lines) + "\n", {"published": times, "twist": twist}

    def call(self, c: Checked, timeout: float) -> tuple[str, Any]:
        name, req = c.command.name, c.message
        response = self.serve(name, req)
        text = (
            f"requester: making request: {python_repr(c.type, req, 0)}\n\n"
            f"response:\n{python_repr(c.type, response, 1)}\n\n"
        )
        return text, response

    def serve(self, name: str, req: dict) -> dict:
        sim = self.sim
        if name == "/list_locations":
            locs = self.store.list_locations() if self.store else []
            return {
                "names": [loc.name for loc in locs],
                "poses": [{"x": loc.x, "y": loc.y, "theta": loc.theta} for loc in locs],
            }
        try:
            if name == "/goto_position":
                if req["name"]:
                    x, y, th, label = self._named_pose(req["name"])
                else:
                    x, y, th, label = req["x"], req["y"], req["theta"], ""
                goal = sim.goto(x, y, th, label)
                dist = goal.distance_remaining(*sim.pose[:2])
                return {
                    "success": True,
                    "message": f"navigating to {goal.name}, {dist:.1f} m along the path",
                }
            if name == "/stop":
                return {"success": True, "message": sim.stop()}
            if name == "/release":
                return {"success": True, "message": sim.release()}
            if name == "/dock":
                sim.dock()
                return {"success": True, "message": "docking"}
            if name == "/undock":
                sim.undock()
                return {"success": True, "message": "undocking"}
            if name in ("/conveyor/load", "/conveyor/unload"):
                return {
                    "success": True,
                    "message": sim.conveyor_transfer(1 if name.endswith("/load") else -1),
                }
            if name == "/save_location":
                if self.store is None:
                    return {"success": False, "message": "no location store is attached"}
                x, y, th = sim.pose
                loc = self.store.add_location(req["name"], x, y, th, req["description"])
                return {
                    "success": True,
                    "message": f"saved {loc.name} at ({loc.x:.2f}, {loc.y:.2f})",
                }
        except (GoalError, LocationError) as exc:
            return {"success": False, "message": str(exc)}
        raise BackendError(f"the simulator does not serve {name}")

    def _named_pose(self, name: str) -> tuple[float, float, float, str]:
        if self.store is not None:
            loc = self.store.require_location(name)
            return loc.x, loc.y, loc.theta, loc.name
        st = self.sim.map.station(name)
        if st is None:
            raise LocationError(f"no location named '{name}'")
        return (*st.pose, st.name)

    def send_goal(self, c: Checked, timeout: float) -> tuple[str, Any]:
        goal_msg = c.message
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
        feedback = "feedback" in c.command.flags
        start = self.sim.t
        # manual clock: the goal may take minutes of robot time; real time: `timeout` of wall
        limit = 900.0 if not self.realtime else timeout
        wall0 = time.monotonic()
        while self.sim.goal is not None and self.sim.goal.id == goal.id:
            if (not self.realtime and self.sim.t - start > limit) or (
                self.realtime and time.monotonic() - wall0 > limit
            ):
                lines.append(f"Goal still running after {limit:g} s; /stop cancels it")
                return "\n".join(lines) + "\n", {"accepted": True, "status": "RUNNING"}
            self.advance(1.0, timeout)
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
        res = {"error_code": 0 if ok else 1, "error_msg": "" if ok else result.message}
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
        return [(n, name, type_of(value)) for (n, name), value in self.params.items()]

    def get_param(self, node: str, name: str, timeout: float) -> Any:
        return self.params[(node, name)]

    def set_param(self, node: str, name: str, value: Any, timeout: float) -> str:
        self.params[(node, name)] = value
        if name == "max_linear_speed":
            self.sim.gains = type(self.sim.gains)(v_max=value, w_max=self.sim.gains.w_max)
        return ""
