"""The ASTIbot in the warehouse: physics, sensors, battery, conveyor and navigation in one clock.

`step(dt)` advances the sim clock in fixed physics substeps (100 Hz); control runs at 20 Hz and
the lidar at 10 Hz. Every public method takes the lock, so a runner thread may step while other
threads command or read `snapshot()`.
"""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar

import numpy as np

from astiop.sim import lidar
from astiop.sim.base import Base, Pose
from astiop.sim.battery import Battery, LipoBattery
from astiop.sim.body import ASTIBOT_BODY, Body
from astiop.sim.camera import ASTIBOT_CAMERA, Camera, CameraSpec
from astiop.sim.clock import Clock, SimEvents
from astiop.sim.commands import TELEOP_TIMEOUT_S, SimCommands
from astiop.sim.controller import ControllerGains
from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import Goal, GoalError, GoalResult
from astiop.sim.holds import Holds
from astiop.sim.kinematics import (
    ASTIBOT,
    MecanumParams,
    inverse_kinematics,
)
from astiop.sim.navigation import (
    BLOCKED_GIVE_UP_S,
    ROBOT_LENGTH,  # noqa: F401 - the ASTIbot's size, read from here by tests
    ROBOT_WIDTH,  # noqa: F401
    Navigation,
)
from astiop.sim.path_planner import PathPlanner
from astiop.sim.perception import DetectedObstacle
from astiop.sim.scanner import Scanner
from astiop.sim.state import Event, SimState, lamp, state_word
from astiop.sim.stepping import Physics
from astiop.sim.world import Obstacle, World
from astiop.warehouse import WarehouseMap, default_map
from astiop.zones import MapZone

ROBOT_MASS = ASTIBOT_BODY.mass
T = TypeVar("T")


class OwnedBy(Generic[T]):
    """An attribute of the simulator whose state one of its helpers owns: `goal =
    OwnedBy[Goal | None]("navigation")` makes `sim.goal` read and write `sim.navigation.goal`."""

    def __init__(self, helper: str, name: str = "") -> None:
        self.helper, self.name = helper, name

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = self.name or name

    def __get__(self, sim: Any, owner: type | None = None) -> T:
        value: T = getattr(getattr(sim, self.helper), self.name)
        return value

    def __set__(self, sim: Any, value: T) -> None:
        setattr(getattr(sim, self.helper), self.name, value)


class Simulator:
    """The one front of the simulated robot; its state is its helpers': `clock` and `events`,
    `base` (bodies, pose, motors), `holds` (E-STOP, /stop, fault), `scanner` (lidar),
    `navigation` (goals, zones, dock), `commands` and `physics` (the step)."""

    t = OwnedBy[float]("clock")
    goal = OwnedBy[Goal | None]("navigation")
    plan = OwnedBy[tuple[tuple[float, float], ...]]("navigation")
    last_result = OwnedBy[GoalResult | None]("navigation")
    plan_ms = OwnedBy[list[float]]("navigation")
    gains = OwnedBy[ControllerGains]("navigation")
    blocked_give_up_s = OwnedBy[float]("navigation")  # a blocked goal is aborted after this
    zones = OwnedBy[tuple[MapZone, ...]]("navigation")
    zone_source = OwnedBy[Callable[[], Sequence[MapZone]] | None]("navigation")
    e_stopped = OwnedBy[bool]("holds")  # the robot's E-STOP input
    stop_latched = OwnedBy[bool]("holds")  # /stop holds the base, as a safety controller does
    fault = OwnedBy[str]("holds")
    collisions = OwnedBy[int]("physics")
    max_penetration = OwnedBy[float]("physics")
    after_step = OwnedBy[list[Callable[[], Any]]]("physics")  # called after each step()
    scan_ranges = OwnedBy[np.ndarray]("scanner", "ranges")
    scan_stamp = OwnedBy[float]("scanner", "stamp")
    detected = OwnedBy[list[DetectedObstacle]]("scanner")
    lidar_ms = OwnedBy[collections.deque[float]]("scanner", "ms")

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
        battery: Battery | LipoBattery | None = None,
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
        self.params = params
        self.rng = np.random.default_rng(seed)
        self.seed = seed
        self.lock = lock or threading.RLock()
        self.dt = 1.0 / physics_hz
        self.lidar_enabled = lidar_enabled
        self.lidar_spec = lidar_spec or lidar.LidarSpec()
        self.in_fleet = world is not None
        self.world = world or World(self.map)
        self.path_planner = PathPlanner(self.world.static_boxes, self.map.bounds, body.inflation)
        self.battery = battery if battery is not None else Battery(battery_soc)
        self.conveyor = Conveyor()
        self.clock = Clock(self.dt)
        self.events = SimEvents(self.clock)
        self.base = Base(self.world, self._resolve_start(start), body, params, owner=self)
        self.control, self.body, self.shape = self.base.control, self.base.body, self.base.shape
        self.holds = Holds()
        self.scanner = Scanner(self.world, self.base, self.clock, self.lidar_spec, self.rng)
        self.navigation = Navigation(
            lock=self.lock, warehouse=self.map, dock_name=dock, world=self.world,
            planner=self.path_planner, base=self.base, holds=self.holds, scanner=self.scanner,
            clock=self.clock, events=self.events,
            gains=gains or ControllerGains(v_max=v_max, w_max=w_max),
            blocked_give_up_s=blocked_give_up_s,
        )  # fmt: skip
        self.commands = SimCommands(
            lock=self.lock, clock=self.clock, events=self.events, holds=self.holds,
            base=self.base, navigation=self.navigation, conveyor=self.conveyor, world=self.world,
        )  # fmt: skip
        self.physics = Physics(
            lock=self.lock, clock=self.clock, world=self.world, base=self.base, holds=self.holds,
            navigation=self.navigation, scanner=self.scanner, battery=self.battery,
            conveyor=self.conveyor, events=self.events, physics_hz=physics_hz,
            lidar_enabled=lidar_enabled, in_fleet=self.in_fleet,
        )  # fmt: skip
        self.camera = Camera(camera) if camera is not None else None
        if self.lidar_enabled:
            self.scanner.scan()

    def _resolve_start(self, start: tuple[float, float, float] | str | None) -> Pose:
        if start is None or start == "docked":
            dock = self.map.station(self.dock_name)
            return dock.docked_pose if dock and dock.docked_pose else (2.0, 2.0, 0.0)
        if isinstance(start, str):
            st = self.map.station(start)
            if st is None:
                raise GoalError(f"unknown station '{start}'")
            return st.pose
        x, y, theta = (float(v) for v in start)
        return (x, y, theta)

    # -- the clock (physics) -------------------------------------------------------------
    def step(self, duration: float) -> None:
        self.physics.step(duration)

    def run_until(
        self, predicate: Callable[[], bool], max_sim_s: float, chunk: float = 0.1
    ) -> bool:
        return self.physics.run_until(predicate, max_sim_s, chunk)

    def run_goal(self, max_sim_s: float = 900.0) -> GoalResult | None:
        """Step until the active goal ends (fast mode); returns its result."""
        return self.physics.run_goal(max_sim_s)

    # -- goals (navigation) --------------------------------------------------------------
    def set_zones(self, zones: Sequence[MapZone]) -> None:
        self.navigation.set_zones(zones)

    def check_goal(self, x: float, y: float, theta: float) -> None:
        """Raise GoalError if the robot could never stand at this pose."""
        self.navigation.check_goal(x, y, theta)

    def goto(self, x: float, y: float, theta: float, name: str = "") -> Goal:
        return self.navigation.goto(x, y, theta, name)

    def dock(self) -> Goal:
        return self.navigation.dock()

    def undock(self) -> Goal:
        return self.navigation.undock()

    def cancel(self, reason: str = "canceled by the operator") -> bool:
        return self.navigation.cancel(reason)

    # -- commands ------------------------------------------------------------------------
    def stop(self) -> str:
        """Stop all motion, cancel the goal and acknowledge a collision fault; then hold the
        base (no /cmd_vel, goal, dock or conveyor job) until /release."""
        return self.commands.stop()

    def release(self) -> str:
        """/release: let go of a latched /stop and of the E-STOP input."""
        return self.commands.release()

    def set_cmd_vel(
        self, vx: float, vy: float, wz: float, timeout: float = TELEOP_TIMEOUT_S
    ) -> None:
        """Teleop velocity in the robot frame; it lapses unless repeated within `timeout`."""
        self.commands.set_cmd_vel(vx, vy, wz, timeout)

    def clear_fault(self) -> None:
        self.commands.clear_fault()

    def estop(self) -> None:
        self.commands.estop()

    def release_estop(self) -> None:
        self.commands.release_estop()

    def conveyor_transfer(self, direction: int) -> str:
        return self.commands.conveyor_transfer(direction)

    def add_obstacle(self, kind: str, x: float, y: float, theta: float = 0.0) -> Obstacle:
        return self.commands.add_obstacle(kind, x, y, theta)

    def remove_obstacle(self, obstacle_id: int) -> Obstacle:
        return self.commands.remove_obstacle(obstacle_id)

    # -- events --------------------------------------------------------------------------
    def events_since(self, seq: int) -> list[Event]:
        with self.lock:
            return self.events.since(seq)

    # -- state -----------------------------------------------------------------------
    @property
    def pose(self) -> Pose:
        return self.base.pose

    def camera_image(self) -> tuple[float, np.ndarray] | None:
        """The camera's frame of this period: (its time, RGB pixels (height, width, 3)); None
        without a camera. Rendered once per frame, under the lock: the world holds still."""
        if self.camera is None:
            return None
        with self.lock:
            return self.camera.frame(self.world, self.body, self.t)

    def docked(self) -> bool:
        return self.navigation.docked()

    def speed(self) -> float:
        return self.base.speed()

    @property
    def held(self) -> bool:
        """Whether the base holds still until /release: its E-STOP input, or a latched /stop."""
        return self.holds.held

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
            v = self.base.v
            wheels = inverse_kinematics(v[0], v[1], v[2], self.params)
            goal = self.goal
            return SimState(
                t=self.t,
                x=x,
                y=y,
                theta=th,
                vx=float(v[0]),
                vy=float(v[1]),
                wz=float(v[2]),
                wheel_speeds=(
                    float(wheels[0]),
                    float(wheels[1]),
                    float(wheels[2]),
                    float(wheels[3]),
                ),
                state=self.state_word(),
                mode="manual" if self.base.teleop.until > self.t else "auto",
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
                event_seq=self.events.seq,
            )
