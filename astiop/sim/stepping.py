"""The simulator's clock: fixed physics substeps (100 Hz), control, battery and conveyor at
20 Hz, the lidar and obstacle detection at 10 Hz."""

from __future__ import annotations

import collections
import math
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import pymunk

from astiop.sim import lidar
from astiop.sim.body import Body
from astiop.sim.commands import Teleop
from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import Goal, GoalResult
from astiop.sim.kinematics import MecanumParams, achievable_velocity, wheel_speeds
from astiop.sim.perception import DetectedObstacle, detect
from astiop.sim.world import ROBOT_OWNER, World

A_LIN, A_ANG = 1.0, 2.0  # m/s², rad/s² the base ramps with
_SET_VELOCITY = pymunk.Body.velocity.fset
_SET_ANGULAR_VELOCITY = pymunk.Body.angular_velocity.fset


class SteppingHost(Protocol):
    """What `SteppingMixin` needs of the simulator it is mixed into."""

    lock: threading.RLock
    in_fleet: bool
    dt: float
    t: float
    _tick: int
    _carry: float
    _control_every: int
    _lidar_every: int
    after_step: list[Callable[[], Any]]
    world: World
    body: pymunk.Body
    control: pymunk.Body
    chassis: Body
    params: MecanumParams
    battery: Any
    conveyor: Conveyor
    goal: Goal | None
    last_result: GoalResult | None
    fault: str
    e_stopped: bool
    collisions: int
    _contact: str | None
    _teleop: Teleop
    _v: list[float]
    _target: tuple[float, float, float]
    _applied: tuple[float, float, float]
    _motor_power: float
    lidar_enabled: bool
    lidar_spec: lidar.LidarSpec
    lidar_ms: collections.deque[float]
    _beam_angles: np.ndarray
    rng: np.random.Generator
    scan_ranges: np.ndarray
    scan_stamp: float
    detected: list[DetectedObstacle]

    @property
    def pose(self) -> tuple[float, float, float]: ...

    def speed(self) -> float: ...

    def docked(self) -> bool: ...

    def _event(self, kind: str, message: str, severity: str = "info") -> None: ...

    def _navigate(self) -> tuple[float, float, float]: ...

    def _zone_speed(self, target: tuple[float, float, float]) -> tuple[float, float, float]: ...

    def _check_path(self) -> None: ...

    def _finish(self, status: str, message: str) -> None: ...


if TYPE_CHECKING:
    _Host = SteppingHost
else:
    _Host = object


class SteppingMixin(_Host):
    def step(self, duration: float) -> None:
        if self.in_fleet:
            raise RuntimeError("a fleet's robot is stepped by its fleet (SimFleet.step)")
        with self.lock:
            self._carry += duration
            n = int(self._carry / self.dt + 1e-9)
            self._carry -= n * self.dt
            before, world_step, dt = self._before_physics, self.world.step, self.dt
            for _ in range(n):  # a substep: the robot, the world, then its contacts
                before()
                world_step(dt)
                if self._contact is not None:  # _after_physics, inlined
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
        self._teleop = Teleop()
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
        self._target = self._zone_speed(self._target)
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
