"""The ASTIbot in the warehouse: physics, sensors, battery, conveyor and navigation in one clock.

`step(dt)` advances the sim clock in fixed physics substeps (100 Hz); control runs at 20 Hz and
the lidar at 10 Hz. Every public method takes the lock, so a runner thread may step while other
threads command or read `snapshot()`.
"""

from __future__ import annotations

import collections
import math
import threading

import numpy as np

from astiop.sim import lidar
from astiop.sim.battery import Battery
from astiop.sim.body import ASTIBOT_BODY, Body
from astiop.sim.camera import ASTIBOT_CAMERA, Camera, CameraSpec
from astiop.sim.commands import CommandsMixin, Teleop
from astiop.sim.controller import ControllerGains, tracking_error
from astiop.sim.conveyor import Conveyor
from astiop.sim.geometry import wrap_angle
from astiop.sim.goal import Goal, GoalResult
from astiop.sim.kinematics import (
    ASTIBOT,
    MecanumParams,
    inverse_kinematics,
)
from astiop.sim.navigation import (
    BLOCKED_GIVE_UP_S,
    ROBOT_LENGTH,  # noqa: F401 - the ASTIbot's size, read from here by tests
    ROBOT_WIDTH,  # noqa: F401
    GoalError,
    NavigationMixin,
)
from astiop.sim.path_planner import PathPlanner
from astiop.sim.perception import DetectedObstacle
from astiop.sim.state import Event, SimState, lamp, state_word
from astiop.sim.stepping import SteppingMixin
from astiop.sim.world import CT_OBSTACLE, CT_STATIC, World
from astiop.warehouse import WarehouseMap, default_map

ROBOT_MASS = ASTIBOT_BODY.mass


class Simulator(NavigationMixin, CommandsMixin, SteppingMixin):
    def __init__(
        self,
        warehouse: WarehouseMap | None = None,
        *,
        seed: int = 0,
        start: tuple[float, float, float] | str | None = None,
        battery_soc: float = 0.85,
        params: MecanumParams = ASTIBOT,
        physics_hz: int = 100,
        lidar_enabled: bool = True,
        v_max: float = 0.8,
        w_max: float = 0.8,
        blocked_give_up_s: float = BLOCKED_GIVE_UP_S,
        body: Body = ASTIBOT_BODY,
        gains: ControllerGains | None = None,
        battery=None,
        lidar_spec: lidar.LidarSpec | None = None,
        world: World | None = None,
        lock: threading.RLock | None = None,
        dock: str = "charging_dock",
        name: str = "robot",
        camera: CameraSpec | None = ASTIBOT_CAMERA,
    ):
        """`body`, `gains`, `battery` and `lidar_spec` make another robot in the same
        warehouse (a TurtleBot3); `params` is the body's wheels when `body` is the ASTIbot's.
        `world` and `lock` make it one robot of a fleet (`sim/fleet.py` steps them all);
        `dock` is the station it charges at; `camera` None: the robot has none."""
        self.map = warehouse or default_map()
        self.name = name
        self.dock_name = dock
        self.chassis = body  # `self.body` is the pymunk body
        if body is not ASTIBOT_BODY:
            params = body.wheels
        self.blocked_give_up_s = blocked_give_up_s  # a blocked goal is aborted after this
        self.params = params
        self.rng = np.random.default_rng(seed)
        self.seed = seed
        self.lock = lock or threading.RLock()
        self.dt = 1.0 / physics_hz
        self._control_every = max(1, physics_hz // 20)
        self._lidar_every = max(1, physics_hz // 10)
        self.lidar_enabled = lidar_enabled
        self.lidar_spec = lidar_spec or lidar.LidarSpec()
        self._beam_angles = self.lidar_spec.beam_angles()
        self.gains = gains or ControllerGains(v_max=v_max, w_max=w_max)
        self.in_fleet = world is not None
        self.world = world or World(self.map)
        self.path_planner = PathPlanner(self.world.static_boxes, self.map.bounds, body.inflation)
        self.battery = battery if battery is not None else Battery(battery_soc)
        self.conveyor = Conveyor()
        self._build_robot(self._resolve_start(start))
        self.t = 0.0
        self._tick = 0
        self._carry = 0.0
        self.after_step: list = []  # called after each step(), outside the lock
        self._v = [0.0, 0.0, 0.0]  # body velocity being applied (robot frame), floats: per step
        self._applied = (0.0, 0.0, 0.0)
        self._target = (0.0, 0.0, 0.0)
        self._teleop = Teleop()
        self.goal: Goal | None = None
        self.plan: tuple[tuple[float, float], ...] = ()
        self.last_result: GoalResult | None = None
        self._goal_ids = 0
        self.e_stopped = False  # the robot's E-STOP input
        self.stop_latched = False  # /stop holds the base, as a safety controller does
        self._ignored_said = False  # /cmd_vel ignored during this hold: said once
        self.fault = ""
        self.max_penetration = 0.0
        self.collisions = 0
        self._contact: str | None = None
        self.scan_ranges = np.full(self.lidar_spec.beams, np.inf)
        self.scan_stamp = 0.0
        self.detected: list[DetectedObstacle] = []
        self.camera = Camera(camera) if camera is not None else None
        self.lidar_ms: collections.deque[float] = collections.deque(maxlen=2000)
        self.plan_ms: list[float] = []
        self._events: collections.deque[Event] = collections.deque(maxlen=500)
        self._event_seq = 0
        self._motor_power = 0.0
        self._energy_dt = 0.0
        self._pose_at = (-1, (0.0, 0.0, 0.0))  # (world step, pose): the body moves only in a step
        self._dock_at: tuple = (None, None, None)  # (map, dock name, station)
        if self.lidar_enabled:
            self._scan()

    # -- construction ----------------------------------------------------------------
    def _resolve_start(self, start) -> tuple[float, float, float]:
        if start is None or start == "docked":
            dock = self.map.station(self.dock_name)
            return dock.docked_pose if dock and dock.docked_pose else (2.0, 2.0, 0.0)
        if isinstance(start, str):
            st = self.map.station(start)
            if st is None:
                raise GoalError(f"unknown station '{start}'")
            return st.pose
        return tuple(float(v) for v in start)

    def _build_robot(self, pose) -> None:
        self.control, self.body, self.shape = self.world.add_robot(
            pose, self.chassis.mass, self.chassis.length, self.chassis.width, self
        )
        for other in (CT_STATIC, CT_OBSTACLE):
            self.world.space.on_collision(
                self.shape.collision_type, other, begin=self._on_contact, post_solve=self._on_depth
            )

    def _on_contact(self, arbiter, space, data) -> None:
        other = arbiter.shapes[1] if arbiter.shapes[0] is self.shape else arbiter.shapes[0]
        self._contact = getattr(other, "kind", "obstacle")

    def _on_depth(self, arbiter, space, data) -> None:
        for p in arbiter.contact_point_set.points:
            if -p.distance > self.max_penetration:
                self.max_penetration = -p.distance

    # -- events ----------------------------------------------------------------------
    def _event(self, kind: str, message: str, severity: str = "info") -> None:
        self._event_seq += 1
        self._events.append(Event(self._event_seq, self.t, kind, severity, message))

    def events_since(self, seq: int) -> list[Event]:
        with self.lock:
            return [e for e in self._events if e.seq > seq]

    # -- state -----------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        step, pose = self._pose_at
        if step != self.world.steps:  # read once per physics step, not per use
            p = self.body.position
            pose = (p.x, p.y, wrap_angle(self.body.angle))
            self._pose_at = (self.world.steps, pose)
        return pose

    def camera_image(self) -> tuple[float, np.ndarray] | None:
        """The camera's frame of this period: (its time, RGB pixels (height, width, 3)); None
        without a camera. Rendered once per frame, under the lock: the world holds still."""
        if self.camera is None:
            return None
        with self.lock:
            return self.camera.frame(self.world, self.body, self.t)

    def _dock(self):
        """The dock station, looked up once per map and dock name (`docked()` is 20 Hz)."""
        held_map, held_name, dock = self._dock_at
        if held_map is not self.map or held_name != self.dock_name:
            dock = self.map.station(self.dock_name)
            self._dock_at = (self.map, self.dock_name, dock)
        return dock

    def docked(self) -> bool:
        dock = self._dock()
        if dock is None or dock.docked_pose is None:
            return False
        pose = self.pose
        dx, dy, _ = dock.docked_pose
        if abs(dx - pose[0]) > 0.09 or abs(dy - pose[1]) > 0.09:
            return False  # surely more than 0.08 m off, the error below turned or not (20 Hz)
        ex, ey, eth = tracking_error(pose, dock.docked_pose)
        return math.hypot(ex, ey) < 0.08 and abs(eth) < math.radians(5) and self.speed() < 0.05

    def speed(self) -> float:
        return float(math.hypot(self._v[0], self._v[1]))

    @property
    def held(self) -> bool:
        """Whether the base holds still until /release: its E-STOP input, or a latched /stop."""
        return self.e_stopped or self.stop_latched

    def state_word(self) -> str:
        goal = self.goal
        return state_word(
            e_stopped=self.held,  # held by /stop reads as held by the E-STOP: /release ends both
            fault=self.fault,
            goal_kind=None if goal is None else goal.current.kind,
            blocked=goal is not None and goal.blocked_since is not None,
            docked=self.docked(),
            charging=self.battery.charging,
        )

    def snapshot(self) -> SimState:
        with self.lock:
            x, y, th = self.pose
            wheels = inverse_kinematics(*self._v, self.params)
            goal = self.goal
            return SimState(
                t=self.t,
                x=x,
                y=y,
                theta=th,
                vx=float(self._v[0]),
                vy=float(self._v[1]),
                wz=float(self._v[2]),
                wheel_speeds=tuple(float(w) for w in wheels),
                state=self.state_word(),
                mode="manual" if self._teleop.until > self.t else "auto",
                active_goal=goal.name if goal else "",
                fault=self.fault,
                e_stopped=self.e_stopped,
                stop_latched=self.stop_latched,
                docked=self.docked(),
                battery_soc=self.battery.soc,
                battery_voltage=self.battery.voltage,
                battery_current=self.battery.current,
                battery_charging=self.battery.charging,
                conveyor_loaded=self.conveyor.loaded,
                conveyor_direction=self.conveyor.direction,
                sensor_entry=self.conveyor.sensor_entry,
                sensor_seated=self.conveyor.sensor_seated,
                lamp=lamp(self.state_word(), self.conveyor.running, self.speed(), self.goal),
                scan_ranges=self.scan_ranges.copy(),
                scan_stamp=self.scan_stamp,
                detected=tuple(self.detected),
                plan=self.plan,
                distance_remaining=goal.distance_remaining(x, y) if goal else 0.0,
                goal_id=goal.id if goal else 0,
                last_result=self.last_result,
                obstacles=tuple(self.world.obstacles.values()),
                max_penetration=self.max_penetration,
                collisions=self.collisions,
                event_seq=self._event_seq,
            )
