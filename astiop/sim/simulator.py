"""The ASTIbot in the warehouse: physics, sensors, battery, conveyor and navigation in one clock.

`step(dt)` advances the sim clock in fixed physics substeps (100 Hz); control runs at 20 Hz and
the lidar at 10 Hz. Every public method takes the lock, so a runner thread may step while other
threads command or read `snapshot()`.
"""

from __future__ import annotations

import collections
import math
import threading
import time
from dataclasses import dataclass

import numpy as np
import pymunk

from astiop.sim import lidar
from astiop.sim.battery import Battery
from astiop.sim.body import ASTIBOT_BODY, Body
from astiop.sim.controller import ControllerGains, tracking_error
from astiop.sim.conveyor import Conveyor
from astiop.sim.geometry import wrap_angle
from astiop.sim.goal import Goal, GoalResult
from astiop.sim.kinematics import (
    ASTIBOT,
    MecanumParams,
    achievable_velocity,
    inverse_kinematics,
    wheel_speeds,
)
from astiop.sim.navigation import (
    BLOCKED_GIVE_UP_S,
    ROBOT_LENGTH,  # noqa: F401 - the ASTIbot's size, read from here by tests
    ROBOT_WIDTH,  # noqa: F401
    GoalError,
    NavigationMixin,
)
from astiop.sim.path_planner import PathPlanner
from astiop.sim.perception import DetectedObstacle, detect
from astiop.sim.state import Event, SimState, lamp, state_word
from astiop.sim.world import CT_OBSTACLE, CT_STATIC, ROBOT_OWNER, World
from astiop.warehouse import WarehouseMap, default_map

ROBOT_MASS = ASTIBOT_BODY.mass
TELEOP_TIMEOUT_S = 0.5
STOP_LATCHED = "the stop is latched: /release to move again"
A_LIN, A_ANG = 1.0, 2.0  # m/s², rad/s² the base ramps with
_SET_VELOCITY = pymunk.Body.velocity.fset
_SET_ANGULAR_VELOCITY = pymunk.Body.angular_velocity.fset


@dataclass
class _Teleop:
    v: tuple[float, float, float] = (0.0, 0.0, 0.0)
    until: float = -1.0


class Simulator(NavigationMixin):
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
    ):
        """`body`, `gains`, `battery` and `lidar_spec` make another robot in the same
        warehouse (a TurtleBot3); `params` is the body's wheels when `body` is the ASTIbot's.
        `world` and `lock` make it one robot of a fleet (`sim/fleet.py` steps them all);
        `dock` is the station it charges at."""
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
        self._teleop = _Teleop()
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

    # -- commands --------------------------------------------------------------------
    def _check_can_move(self) -> None:
        if self.e_stopped:
            raise GoalError("the robot is e-stopped; release the e-stop first")
        if self.stop_latched:
            raise GoalError(STOP_LATCHED)
        if self.fault:
            raise GoalError(f"the robot has a fault ({self.fault}); call /stop to acknowledge it")

    def stop(self) -> str:
        """Stop all motion, cancel the goal and acknowledge a collision fault; then hold the
        base (no /cmd_vel, goal, dock or conveyor job) until /release."""
        with self.lock:
            had_goal = self.cancel("stopped by /stop")
            self._teleop = _Teleop()
            self._target = (0.0, 0.0, 0.0)
            if self.fault:
                self._event("fault", f"fault acknowledged: {self.fault}")
                self.fault = ""
            if not self.stop_latched:
                self.stop_latched = True
                self._event("stop", "stop latched: /release to move again", "warning")
            return "stopped; goal canceled" if had_goal else "stopped"

    def release(self) -> str:
        """/release: let go of a latched /stop and of the E-STOP input."""
        with self.lock:
            if not self.held:
                return "released; nothing was held"
            if self.e_stopped:
                self.e_stopped = False
                self._event("estop", "e-stop released")
            if self.stop_latched:
                self.stop_latched = False
                self._event("stop", "stop released: the robot may move again")
            self._ignored_said = False  # the next hold says it again
            return "released: the robot may move again"

    def set_cmd_vel(
        self, vx: float, vy: float, wz: float, timeout: float = TELEOP_TIMEOUT_S
    ) -> None:
        """Teleop velocity in the robot frame; it lapses unless repeated within `timeout`.
        Held (E-STOP, latched /stop), the base stays at rest: a zero Twist agrees with that,
        any other is refused and said once per hold."""
        with self.lock:
            if self.held:
                if vx == vy == wz == 0.0:
                    return
                self._say_ignored()
            self._check_can_move()
            if self.goal is not None:
                self.cancel("overridden by /cmd_vel")
            self._teleop = _Teleop((float(vx), float(vy), float(wz)), self.t + timeout)

    def clear_fault(self) -> None:
        """For a base with no fault latch (a TurtleBot3's motors just stall against a wall):
        its next command moves it again."""
        with self.lock:
            if self.fault:
                self._event("fault", f"cleared by the next command: {self.fault}")
                self.fault = ""

    def _say_ignored(self) -> None:
        if not self._ignored_said:
            self._ignored_said = True
            why = "the robot is e-stopped" if self.e_stopped else "the stop is latched"
            self._event("stop", f"/cmd_vel ignored: {why} (/release to move again)", "warning")

    def _clear_teleop(self) -> None:
        self._teleop = _Teleop()

    def estop(self) -> None:
        with self.lock:
            if not self.e_stopped:
                self.e_stopped = True
                self.cancel("e-stop")
                self.conveyor.abort()
                self._teleop = _Teleop()
                self._v[:] = (0.0, 0.0, 0.0)
                self.control.velocity, self.control.angular_velocity = (0, 0), 0.0
                self._applied = (0.0, 0.0, 0.0)
                self._event("estop", "E-STOP engaged", "error")

    def release_estop(self) -> None:
        """The E-STOP's release is the robot's /release: it lets go of a latched /stop too."""
        self.release()

    def conveyor_transfer(self, direction: int) -> str:
        with self.lock:
            self._check_can_move()
            word = "load" if direction > 0 else "unload"
            if self.conveyor.running:
                raise GoalError("the conveyor is already running")
            if self.goal is not None or self.speed() > 0.02:
                raise GoalError(f"cannot {word} while moving")
            st, dist = self.world.nearest_station(*self.pose[:2])
            if st is None or st.kind != "conveyor" or dist > 0.3:
                raise GoalError(
                    f"cannot {word} here: not at a conveyor station "
                    "(assembly_station, cps_storage, shipping)"
                )
            if direction > 0 and self.conveyor.loaded:
                raise GoalError("the conveyor already carries a load")
            if direction < 0 and not self.conveyor.loaded:
                raise GoalError("the conveyor is empty: nothing to unload")
            self.conveyor.start(direction)
            self._event("conveyor", f"{word}ing at {st.name}")
            return f"{word}ing at {st.name}"

    def add_obstacle(self, kind: str, x: float, y: float, theta: float = 0.0):
        with self.lock:
            ob = self.world.add_obstacle(kind, x, y, theta)
            self._event("world", f"{kind} {ob.id} placed at ({x:.1f}, {y:.1f})")
            return ob

    def remove_obstacle(self, obstacle_id: int):
        with self.lock:
            ob = self.world.remove_obstacle(obstacle_id)
            self._event("world", f"{ob.kind} {ob.id} removed")
            return ob

    # -- time ------------------------------------------------------------------------
    def step(self, duration: float) -> None:
        if self.in_fleet:
            raise RuntimeError("a fleet's robot is stepped by its fleet (SimFleet.step)")
        with self.lock:
            self._carry += duration
            n = int(self._carry / self.dt + 1e-9)
            self._carry -= n * self.dt
            before, world_step, dt = self._before_physics, self.world.step, self.dt
            for _ in range(n):  # _substep, with its lookups made once
                before()
                world_step(dt)
                if self._contact is not None:  # _after_physics
                    self._on_collision(self._contact)
        for observe in self.after_step:  # e.g. a recorder, in fast mode
            observe()

    def run_until(self, predicate, max_sim_s: float, chunk: float = 0.1) -> bool:
        end = self.t + max_sim_s
        while self.t < end:
            if predicate():
                return True
            self.step(chunk)
        return predicate()

    def run_goal(self, max_sim_s: float = 900.0) -> GoalResult | None:
        """Step until the active goal ends (fast mode); returns its result."""
        self.run_until(lambda: self.goal is None, max_sim_s)
        if self.goal is not None:
            with self.lock:
                self._finish("aborted", f"timed out after {max_sim_s:.0f} s")
        return self.last_result

    def _substep(self) -> None:
        self._before_physics()
        self.world.step(self.dt)
        self._after_physics()

    def _before_physics(self) -> None:
        """The robot's share of a substep before the world moves: control, lidar, its motors.
        100 Hz: written for speed (min(d, max(-d, x)) spelled as comparisons, same values)."""
        tick = self._tick = self._tick + 1
        dt = self.dt
        self.t = tick * dt
        if tick % self._control_every == 0:
            self._control(dt * self._control_every)
        if self.lidar_enabled and tick % self._lidar_every == 0:
            self._scan()
            if self.goal is not None:
                self._check_path()
        v = self._v
        if self.e_stopped or self.fault:
            v[:] = vx, vy, wz = (0.0, 0.0, 0.0)
        else:
            tx, ty, tw = self._target
            vx, vy, wz = v
            dl, da = A_LIN * dt, A_ANG * dt
            d = tx - vx
            vx += d if -dl < d < dl else (dl if d >= dl else -dl)
            d = ty - vy
            vy += d if -dl < d < dl else (dl if d >= dl else -dl)
            d = tw - wz
            wz += d if -da < d < da else (da if d >= da else -da)
            v[:] = vx, vy, wz
        th = self.body.angle
        c, s = math.cos(th), math.sin(th)
        command = (c * vx - s * vy, s * vx + c * vy, wz)
        applied = self._applied
        if command != applied:  # pymunk's attribute setters cost more than the check
            self._applied = command
            # the properties' own setters (pymunk.Body's __setattr__ hook doubles their cost);
            # setting a kinematic body's velocity to the value it has is no change: skipped
            if command[:2] != applied[:2]:
                _SET_VELOCITY(self.control, command[:2])
            if wz != applied[2]:
                _SET_ANGULAR_VELOCITY(self.control, wz)

    def _after_physics(self) -> None:
        if self._contact is not None:
            self._on_collision(self._contact)

    def _on_collision(self, kind: str) -> None:
        self._contact = None
        if self.fault or self.speed() < 0.05 and self.goal is None and self._teleop.until < self.t:
            return
        self.collisions += 1
        self.fault = f"collision with {kind.split(':')[0]}"
        self._v[:] = (0.0, 0.0, 0.0)
        self._target = (0.0, 0.0, 0.0)
        self._teleop = _Teleop()
        self.control.velocity, self.control.angular_velocity = (0, 0), 0.0
        self._applied = (0.0, 0.0, 0.0)
        self._finish("aborted", self.fault)
        self._event("fault", f"{self.fault} at ({self.pose[0]:.2f}, {self.pose[1]:.2f})", "error")

    # -- 20 Hz: control, battery, conveyor -----------------------------------------------
    def _control(self, dt: float) -> None:
        if self.goal is not None:
            self._target = self._navigate()
            if self.chassis.differential:  # the small wheels' top speed bounds the controller
                self._target = achievable_velocity(*self._target, self.params)
        elif self._teleop.until >= self.t:
            vx, vy, wz = self._teleop.v
            if self.chassis.differential:
                vy = 0.0  # no lateral motion; the wheels' limit bounds the rest
            self._target = achievable_velocity(vx, vy, wz, self.params)
        else:
            self._target = (0.0, 0.0, 0.0)
        w = wheel_speeds(*self._v, self.params)
        self._motor_power = self.chassis.motor_power(w)
        self.battery.update(dt, self._motor_power, on_charger=self.docked())
        done = self.conveyor.update(dt)
        if done:
            self._event("conveyor", f"{done}")

    # -- 10 Hz: lidar, obstacles, re-planning -----------------------------------------------
    def _scan(self) -> None:
        t0 = time.perf_counter()
        edges, owner, unmapped_edges = self.world.lidar_edges(self.body)
        x, y, th = self.pose
        ranges, hit = lidar.cast_edges(x, y, th, edges, self.lidar_spec, hits=unmapped_edges)
        self.lidar_ms.append((time.perf_counter() - t0) * 1e3)
        self.scan_ranges = lidar.add_noise(ranges, self.rng, self.lidar_spec)
        self.scan_stamp = self.t
        if not unmapped_edges:  # every edge is the map's: nothing to detect
            self.detected = []
            return
        owners = owner[np.maximum(hit, 0)]
        unmapped = (hit >= 0) & (owners >= 0)
        robots = None
        if len(self.world.robots) > 1:
            robots = np.where(unmapped & (owners >= ROBOT_OWNER), owners - ROBOT_OWNER, -1)
        self.detected = detect(self.scan_ranges, unmapped, self._beam_angles, (x, y, th), robots)
