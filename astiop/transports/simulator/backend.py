"""The robot graph served by the simulator: topics at their rates, services, the action."""

from __future__ import annotations

import math
import time
from collections import deque
from typing import Any

from astiop.ros2.catalog import CAMERA_TOPICS, Catalog, astibot_catalog
from astiop.ros2.interfaces import default_value
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.transport import Transport
from astiop.sim import messages as sm
from astiop.sim.runner import SimRunner
from astiop.sim.simulator import GoalError, Simulator
from astiop.store import LocationError, Store
from astiop.transports.base import BackendError, RobotTransport, command_of
from astiop.transports.inflight import InFlight
from astiop.transports.simulator.verbs import SimVerbs
from astiop.transports.state import RobotEvent, RobotState, TopicStat, from_messages


class SimBackend(RobotTransport):
    name = "sim"

    def __init__(
        self,
        sim: Simulator,
        store: Store | None = None,
        *,
        realtime: bool = False,
        speed: float = 1.0,
        stepped_elsewhere: bool = False,
    ):
        """`realtime`: a runner thread steps the simulator (its own, or with
        `stepped_elsewhere` its fleet's: `sim/fleet.py`); else waiting steps it."""
        self.sim = sim
        self.store = store
        if store is not None:  # the map's zones, read again at each goal: plain geometry
            sim.zone_source = store.list_zones
        self.realtime = realtime or stepped_elsewhere
        own = realtime and not stepped_elsewhere
        self._runner = SimRunner(sim, speed=speed) if own else None
        self.catalog: Catalog = astibot_catalog(camera=sim.camera is not None)
        self.params = {k: p.value for k, p in self.catalog.params.items()}
        self.inflight = InFlight()
        self.last_twist: dict | None = None
        self.last_twist_t = -math.inf
        self._samples: dict[str, deque] = {}
        self._plan_count = 0
        self._plan_last_t = -math.inf
        self.verbs = SimVerbs(self)  # what the verbs run on (ros2/verbs/transport.py)

    # -- lifecycle, e-stop -----------------------------------------------------------
    def start(self) -> None:
        if self._runner is not None:
            self._runner.start()

    def close(self) -> None:
        if self._runner is not None:
            self._runner.stop()

    @property
    def e_stopped(self) -> bool:
        return self.sim.e_stopped or self.inflight.held

    def estop(self) -> list[str]:
        failures = self.inflight.stop_all()  # a timed publish sends nothing more
        self.sim.estop()
        return failures

    def release_estop(self, *, robot: bool = True) -> list[str]:
        self.inflight.release()
        self.sim.release()  # the E-STOP and a latched /stop: the operator's release is both
        return []

    # -- commands and services ------------------------------------------------------
    def execute(
        self, checked: Checked, timeout: float = 10.0, on: Transport | None = None
    ) -> tuple[str, Any]:
        """`on`: what the verb runs on, if not this simulator alone (a robot program's view)."""
        cmd = command_of(checked)
        if checked.kind == "actuate" and self.sim.e_stopped and cmd.name != "/stop":
            raise BackendError("the E-STOP is engaged: nothing was sent")
        try:
            with self.actuating(checked):  # refused while the E-STOP holds, ended by it
                return VERBS[cmd.key].run(on or self.verbs, checked, timeout)
        except (GoalError, LocationError) as exc:
            raise BackendError(str(exc)) from None
        except BackendError:
            raise
        except Exception as exc:  # the simulator must never take the caller down
            raise BackendError(f"the simulator failed: {type(exc).__name__}: {exc}") from None

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

    # -- live state -------------------------------------------------------------------
    def robot_time(self) -> float:
        return self.sim.t  # the simulator stamps its messages with its own clock

    def state(self) -> RobotState:
        snap = self.sim.snapshot()
        messages = {name: self.message(name, snap) for name in self.catalog.state_topics()}
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
        if name in CAMERA_TOPICS:  # rendered once per frame, only when read
            frame = self.sim.camera_image()
            if frame is None:
                raise BackendError(f"no {name}: the robot has no camera")
            build = sm.image if name == CAMERA_TOPICS[0] else sm.compressed_image
            return build(*frame)
        if name == "/cmd_vel":
            return self.last_twist or default_value("geometry_msgs/msg/Twist")
        return builders[name](s)

    def message_times(self, names) -> dict[str, float]:
        times = {name: self._last_publish(name) for name in names if name in self.catalog.topics}
        return {name: t for name, t in times.items() if t > -math.inf}

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

    def next_message(self, name: str, timeout: float) -> dict[str, Any]:
        """The topic's next message, at its next publication on the simulator's clock (a latched
        topic's, or /plan's: the one it last published)."""
        spec = self.catalog.topics[name]
        if spec.rate_hz == 0 or name == "/plan":
            if name == "/plan" and self.sim.goal is None:
                raise BackendError("no message on /plan: the robot has no active goal")
            if self._last_publish(name) == -math.inf:
                raise BackendError(f"no reading from {name}: nothing has published it yet")
            return self.message(name)
        period = 1.0 / spec.rate_hz
        next_t = (math.floor(self.sim.t / period + 1e-9) + 1) * period
        self.advance(next_t - self.sim.t, timeout)
        return self.message(name)
