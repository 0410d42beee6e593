"""The ros2 verbs served by the simulator: each checked command answered as `ros2` would,
from the simulator's state (topic, service, action, node, interface, param)."""

from __future__ import annotations

import time
import uuid
from typing import Any

from astiop.ros2.interfaces import interface_show, python_repr
from astiop.ros2.printing import (
    echo_text,
    indent_yaml,
    interface_list_text,
    list_text,
    node_info_text,
    param_list_text,
    type_of,
)
from astiop.ros2.validation import Checked
from astiop.sim.simulator import GoalError
from astiop.store import LocationError
from astiop.transports.base import BackendError
from astiop.transports.state import yaw_of
from astiop.transports.verb_table import ServesVerbs, runs


class SimVerbs(ServesVerbs):
    """Mixed into SimBackend: uses its sim, store, catalog, params and topic messages."""

    # -- execution ------------------------------------------------------------------
    def execute(self, checked: Checked, timeout: float = 10.0) -> tuple[str, Any]:
        cmd = checked.command
        if checked.kind == "actuate" and self.sim.e_stopped and cmd.name != "/stop":
            raise BackendError("the E-STOP is engaged: nothing was sent")
        handler = self.verb_handler(cmd.key)
        if handler is None:
            raise BackendError(f"ros2 {cmd.verb} {cmd.sub} is not served by the simulator")
        try:
            with self.actuating(checked):  # refused while the E-STOP holds, ended by it
                return handler(checked, timeout)
        except (GoalError, LocationError) as exc:
            raise BackendError(str(exc)) from None
        except BackendError:
            raise
        except Exception as exc:  # the simulator must never take the caller down
            raise BackendError(f"the simulator failed: {type(exc).__name__}: {exc}") from None

    @runs("topic list")
    def _topic_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.topics, c)

    @staticmethod
    def _listing(entries: dict, c: Checked) -> tuple[str, list[str]]:
        return list_text(sorted((n, e.type) for n, e in entries.items()), c.command.flags)

    @runs("topic type", "service type")
    def _topic_type(self, c: Checked, timeout: float):
        return c.type + "\n", c.type

    @runs("topic info")
    def _topic_info(self, c: Checked, timeout: float):
        spec = self.catalog.topics[c.command.name]
        pubs, subs = int(bool(spec.publisher)), int(bool(spec.subscriber))
        text = f"Type: {spec.type}\nPublisher count: {pubs}\nSubscription count: {subs}\n"
        return text, {"type": spec.type, "publishers": pubs, "subscribers": subs}

    @runs("topic echo")
    def _topic_echo(self, c: Checked, timeout: float):
        timeout = c.command.options.get("timeout", timeout)
        msg = self._wait_for_message(c.command.name, timeout)
        return echo_text(msg, c.command), msg

    @runs("topic hz")
    def _topic_hz(self, c: Checked, timeout: float):
        spec = self.catalog.topics[c.command.name]
        if spec.rate_hz == 0 or (c.command.name == "/plan" and self.sim.goal is None):
            raise BackendError(f"{spec.name} is not being published at a rate right now")
        window = c.command.options.get("window", int(spec.rate_hz * 2) + 1)
        duration = min((window - 1) / spec.rate_hz, 5.0)
        self.advance(duration, timeout)
        period = 1.0 / spec.rate_hz
        text = (
            f"average rate: {spec.rate_hz:.3f}\n\tmin: {period:.3f}s max: {period:.3f}s "
            f"std dev: 0.00000s window: {window}\n"
        )
        return text, {"average_rate": spec.rate_hz, "window": window}

    @runs("topic pub")
    def _topic_pub(self, c: Checked, timeout: float):
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

    @runs("service list")
    def _service_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.services, c)

    @runs("service call")
    def _service_call(self, c: Checked, timeout: float):
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

    @runs("action list")
    def _action_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.actions, c)

    @runs("action info")
    def _action_info(self, c: Checked, timeout: float):
        spec = self.catalog.actions[c.command.name]
        text = f"Action: {spec.name}\nAction clients: 0\nAction servers: 1\n    {spec.node}\n"
        return text, {"servers": [spec.node]}

    @runs("action send_goal")
    def _action_send_goal(self, c: Checked, timeout: float):
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

    @runs("node list")
    def _node_list(self, c: Checked, timeout: float):
        return "\n".join(self.catalog.nodes) + "\n", list(self.catalog.nodes)

    @runs("node info")
    def _node_info(self, c: Checked, timeout: float):
        info = self.catalog.node_info(c.command.name)
        return node_info_text(c.command.name, info), info

    @runs("interface show")
    def _interface_show(self, c: Checked, timeout: float):
        return interface_show(c.command.args["type"]), None

    @runs("interface list")
    def _interface_list(self, c: Checked, timeout: float):
        from astiop.ros2.definitions import DEFINITIONS

        return interface_list_text(list(DEFINITIONS), c.command.flags)

    @runs("param list")
    def _param_list(self, c: Checked, timeout: float):
        params = [(node, name, type_of(value)) for (node, name), value in self.params.items()]
        return param_list_text(params, c.command.args.get("node"), c.command.flags,
                               c.command.options)  # fmt: skip

    @runs("param get")
    def _param_get(self, c: Checked, timeout: float):
        key = (c.command.args["node"], c.command.args["param"])
        value = self.params[key]
        word = {float: "Double", int: "Integer", str: "String", bool: "Boolean"}[type(value)]
        return f"{word} value is: {value}\n", value

    @runs("param set")
    def _param_set(self, c: Checked, timeout: float):
        key = (c.command.args["node"], c.command.args["param"])
        value = c.message["value"]
        self.params[key] = value
        if key[1] == "max_linear_speed":
            self.sim.gains = type(self.sim.gains)(v_max=value, w_max=self.sim.gains.w_max)
        return "Set parameter successful\n", value
