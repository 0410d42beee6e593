"""The robot graph served by the simulator: topics at their rates, services, the action."""

from __future__ import annotations

import math
import time
import uuid
from collections import deque
from typing import Any

from astiop.robot import sim_messages as sm
from astiop.robot.catalog import Catalog, astibot_catalog
from astiop.robot.interfaces import default_value, interface_show, python_repr
from astiop.robot.output import BackendError, echo_text, indent_yaml
from astiop.robot.state import RobotEvent, RobotState, TopicStat, from_messages, yaw_of
from astiop.robot.validation import Checked
from astiop.sim.runner import SimRunner
from astiop.sim.simulator import GoalError, Simulator
from astiop.store import LocationError, Store

# What the state is built from: the same messages the robot publishes.
STATE_TOPICS = (
    "/robot_pose",
    "/odom",
    "/battery_status",
    "/robot_status",
    "/obstacles",
    "/plan",
    "/conveyor/status",
)


class SimBackend:
    name = "sim"
    capabilities = frozenset({"commands", "teleop"})

    def __init__(
        self,
        sim: Simulator,
        store: Store | None = None,
        *,
        realtime: bool = False,
        speed: float = 1.0,
    ):
        self.sim = sim
        self.store = store
        self.realtime = realtime
        self._runner = SimRunner(sim, speed=speed) if realtime else None
        self.catalog: Catalog = astibot_catalog()
        self.params = {k: p.value for k, p in self.catalog.params.items()}
        self.last_twist: dict | None = None
        self.last_twist_t = -math.inf
        self._samples: dict[str, deque] = {}
        self._plan_count = 0
        self._plan_last_t = -math.inf

    # -- lifecycle, e-stop -----------------------------------------------------------
    def start(self) -> None:
        if self._runner is not None:
            self._runner.start()

    def close(self) -> None:
        if self._runner is not None:
            self._runner.stop()

    @property
    def e_stopped(self) -> bool:
        return self.sim.e_stopped

    def estop(self) -> list[str]:
        self.sim.estop()
        return []

    def release_estop(self) -> None:
        self.sim.release_estop()

    # -- live state -------------------------------------------------------------------
    def state(self) -> RobotState:
        snap = self.sim.snapshot()
        messages = {name: self.message(name, snap) for name in (*STATE_TOPICS, "/scan")}
        if snap.goal_id == 0:
            del messages["/plan"]
        return from_messages(snap.t, messages, e_stopped=snap.e_stopped, event_seq=snap.event_seq)

    def events_since(self, seq: int) -> list[RobotEvent]:
        return [
            RobotEvent(e.seq, e.t, e.kind, e.severity, e.message)
            for e in self.sim.events_since(seq)
        ]

    def map_geometry(self):
        return self.sim.map

    def drive(self, twist: dict, timeout: float = 0.5) -> None:
        """Hold this velocity for `timeout` s of robot time (teleop, and each `topic pub`)."""
        if self.sim.e_stopped:
            raise BackendError("the E-STOP is engaged")
        try:
            self.sim.set_cmd_vel(
                twist["linear"]["x"], twist["linear"]["y"], twist["angular"]["z"], timeout=timeout
            )
        except GoalError as exc:
            raise BackendError(str(exc)) from None
        self.last_twist, self.last_twist_t = twist, self.sim.t

    # -- clock ----------------------------------------------------------------------
    def advance(self, sim_seconds: float, wall_timeout: float) -> None:
        """Let `sim_seconds` of robot time pass: wait for the runner, or step it ourselves."""
        target = self.sim.t + sim_seconds
        if not self.realtime:
            self.sim.step(max(0.0, target - self.sim.t))
            return
        deadline = time.monotonic() + wall_timeout
        while self.sim.t < target - 1e-9:
            if time.monotonic() > deadline:
                raise BackendError(f"timed out after {wall_timeout:g} s waiting for the robot")
            time.sleep(0.01)

    def wait_until_idle(self, timeout_s: float) -> str | None:
        if not self.realtime:  # step the simulator; waiting never ends the goal itself
            self.sim.run_until(lambda: self.sim.goal is None, timeout_s)
        else:
            deadline = time.monotonic() + timeout_s
            while self.sim.goal is not None and time.monotonic() < deadline:
                time.sleep(0.05)
        if self.sim.goal is not None:
            return None
        result = self.sim.last_result
        return result.status if result else None

    # -- topics ---------------------------------------------------------------------
    def _last_publish(self, name: str) -> float:
        spec = self.catalog.topics[name]
        t = self.sim.t
        if name == "/tf_static":
            return 0.0
        if name == "/cmd_vel":
            return self.last_twist_t
        if name == "/plan":
            return t if self.sim.goal is not None else self._plan_last_t
        return math.floor(t * spec.rate_hz + 1e-9) / spec.rate_hz

    def _count(self, name: str) -> int:
        spec = self.catalog.topics[name]
        if spec.rate_hz == 0:
            return 1 if self._last_publish(name) > -math.inf else 0
        return int(math.floor(self.sim.t * spec.rate_hz + 1e-9))

    def topic_stats(self) -> list[TopicStat]:
        """Rate measured over the last ~2 s of wall time, and the age of the last message."""
        now = time.monotonic()
        stats = []
        for name, spec in self.catalog.topics.items():
            count = self._count(name)
            if name == "/plan" and self.sim.goal is None:
                count = 0
            samples = self._samples.setdefault(name, deque())
            samples.append((now, count))
            while len(samples) > 2 and now - samples[0][0] > 2.0:
                samples.popleft()
            (t0, c0), (t1, c1) = samples[0], samples[-1]
            measured = (c1 - c0) / (t1 - t0) if t1 > t0 and c1 >= c0 else 0.0
            last = self._last_publish(name)
            age = self.sim.t - last if last > -math.inf else math.inf
            stats.append(TopicStat(name, spec.type, spec.rate_hz, measured, age, count))
        return stats

    def message(self, name: str, s=None) -> dict[str, Any]:
        s = s or self.sim.snapshot()
        builders = {
            "/odom": sm.odometry,
            "/robot_pose": sm.robot_pose,
            "/battery_status": sm.battery_state,
            "/robot_status": sm.robot_status,
            "/obstacles": sm.obstacle_array,
            "/conveyor/status": sm.conveyor_status,
            "/plan": sm.path,
            "/diagnostics": sm.diagnostics,
            "/tf": sm.tf,
            "/tf_static": sm.tf_static,
        }
        if name == "/scan":
            return sm.laser_scan(s, self.sim.lidar_spec)
        if name == "/cmd_vel":
            return self.last_twist or default_value("geometry_msgs/msg/Twist")
        return builders[name](s)

    def messages(self, names) -> dict[str, dict[str, Any]]:
        """Every published topic's current message, from one snapshot."""
        s = self.sim.snapshot()
        out = {}
        for name in names:
            if name not in self.catalog.topics or name == "/cmd_vel":
                continue
            if name == "/plan" and self.sim.goal is None:
                continue
            published = self._last_publish(name)
            if published == -math.inf:
                continue
            message = self.message(name, s)
            if "header" in message:  # stamped when the topic last published, as a robot does
                sec = int(published)
                stamp = {"sec": sec, "nanosec": int(round((published - sec) * 1e9))}
                message["header"] = {**message["header"], "stamp": stamp}
            out[name] = message
        return out

    def _wait_for_message(self, name: str, timeout: float) -> dict[str, Any]:
        spec = self.catalog.topics[name]
        if spec.rate_hz == 0 or name == "/plan":
            if name == "/plan" and self.sim.goal is None:
                raise BackendError("no message on /plan: the robot has no active goal")
            if self._last_publish(name) == -math.inf:
                raise BackendError(f"no message on {name}: nothing has published it yet")
            return self.message(name)
        period = 1.0 / spec.rate_hz
        next_t = (math.floor(self.sim.t / period + 1e-9) + 1) * period
        self.advance(next_t - self.sim.t, timeout)
        return self.message(name)

    # -- execution ------------------------------------------------------------------
    def execute(self, checked: Checked, timeout: float = 10.0) -> tuple[str, Any]:
        cmd = checked.command
        if checked.kind == "actuate" and self.sim.e_stopped and cmd.name != "/stop":
            raise BackendError("the E-STOP is engaged: nothing was sent")
        handler = getattr(self, f"_{cmd.verb}_{cmd.sub}")
        try:
            return handler(checked, timeout)
        except (GoalError, LocationError) as exc:
            raise BackendError(str(exc)) from None
        except BackendError:
            raise
        except Exception as exc:  # the simulator must never take the caller down
            raise BackendError(f"the simulator failed: {type(exc).__name__}: {exc}") from None

    def _topic_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.topics, c)

    @staticmethod
    def _listing(entries: dict, c: Checked) -> tuple[str, list[str]]:
        types = "show_types" in c.command.flags
        names = sorted(entries)
        lines = [f"{n} [{entries[n].type}]" if types else n for n in names]
        return "\n".join(lines) + "\n", names

    def _topic_type(self, c: Checked, timeout: float):
        return c.type + "\n", c.type

    def _topic_info(self, c: Checked, timeout: float):
        spec = self.catalog.topics[c.command.name]
        pubs, subs = int(bool(spec.publisher)), int(bool(spec.subscriber))
        text = f"Type: {spec.type}\nPublisher count: {pubs}\nSubscription count: {subs}\n"
        return text, {"type": spec.type, "publishers": pubs, "subscribers": subs}

    def _topic_echo(self, c: Checked, timeout: float):
        timeout = c.command.options.get("timeout", timeout)
        msg = self._wait_for_message(c.command.name, timeout)
        return echo_text(msg, c.command), msg

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

    def _topic_pub(self, c: Checked, timeout: float):
        cmd = c.command
        twist = c.message
        times = 1 if "once" in cmd.flags else cmd.options["times"]
        rate = cmd.options.get("rate", 1.0)
        lines = ["publisher: beginning loop"]
        for i in range(times):
            self.drive(twist, 0.5 if times == 1 else max(0.5, 1.5 / rate))
            lines.append(f"publishing #{i + 1}: {python_repr('geometry_msgs/msg/Twist', twist)}")
            lines.append("")
            if i + 1 < times:
                self.advance(1.0 / rate, timeout + 1.0 / rate)
        return "\n".join(lines) + "\n", {"published": times, "twist": twist}

    def _service_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.services, c)

    _service_type = _topic_type

    def _service_call(self, c: Checked, timeout: float):
        name, req = c.command.name, c.message
        response = self._serve(name, req)
        text = (
            f"requester: making request: {python_repr(c.type, req, 0)}\n\n"
            f"response:\n{python_repr(c.type, response, 1)}\n\n"
        )
        return text, response

    def _serve(self, name: str, req: dict) -> dict:
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

    def _action_list(self, c: Checked, timeout: float):
        return self._listing(self.catalog.actions, c)

    def _action_info(self, c: Checked, timeout: float):
        spec = self.catalog.actions[c.command.name]
        text = f"Action: {spec.name}\nAction clients: 0\nAction servers: 1\n    {spec.node}\n"
        return text, {"servers": [spec.node]}

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

    def _node_list(self, c: Checked, timeout: float):
        return "\n".join(self.catalog.nodes) + "\n", list(self.catalog.nodes)

    def _node_info(self, c: Checked, timeout: float):
        info = self.catalog.node_info(c.command.name)
        lines = [c.command.name]
        for section, items in info.items():
            lines.append(f"  {section}:")
            lines += [f"    {n}: {t}" for n, t in items]
        return "\n".join(lines) + "\n", info

    def _interface_show(self, c: Checked, timeout: float):
        return interface_show(c.command.args["type"]), None

    def _interface_list(self, c: Checked, timeout: float):
        from astiop.robot.definitions import DEFINITIONS

        names = sorted(DEFINITIONS)
        return "\n".join(f"    {n}" for n in names) + "\n", names

    def _param_list(self, c: Checked, timeout: float):
        node = c.command.args.get("node")
        lines, values = [], {}
        for n in self.catalog.nodes:
            if node and n != node:
                continue
            names = [p for (pn, p) in self.params if pn == n]
            if names:
                lines.append(f"{n}:")
                lines += [f"  {p}" for p in sorted(names)]
                values[n] = sorted(names)
        return "\n".join(lines) + "\n", values

    def _param_get(self, c: Checked, timeout: float):
        key = (c.command.args["node"], c.command.args["param"])
        value = self.params[key]
        word = {float: "Double", int: "Integer", str: "String", bool: "Boolean"}[type(value)]
        return f"{word} value is: {value}\n", value

    def _param_set(self, c: Checked, timeout: float):
        key = (c.command.args["node"], c.command.args["param"])
        value = c.message["value"]
        self.params[key] = value
        if key[1] == "max_linear_speed":
            self.sim.gains = type(self.sim.gains)(v_max=value, w_max=self.sim.gains.w_max)
        return "Set parameter successful\n", value
