"""The simulator's clock: fixed physics substeps (100 Hz), control, battery and conveyor at
20 Hz, the lidar and obstacle detection at 10 Hz; the base's contacts and the collision fault."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pymunk

from astiop.sim.base import Base
from astiop.sim.battery import Battery, LipoBattery
from astiop.sim.clock import Clock, SimEvents
from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import GoalResult
from astiop.sim.holds import Holds
from astiop.sim.kinematics import achievable_velocity, wheel_speeds
from astiop.sim.navigation import Navigation
from astiop.sim.scanner import Scanner
from astiop.sim.world import CT_OBSTACLE, CT_STATIC, World


class Physics:
    """Steps the clock and, each substep, the robot's share of it: its controller, lidar and
    motors, then the world (alone, or the fleet's `SimFleet.step`), then its contacts."""

    def __init__(
        self,
        *,
        lock: threading.RLock,
        clock: Clock,
        world: World,
        base: Base,
        holds: Holds,
        navigation: Navigation,
        scanner: Scanner,
        battery: Battery | LipoBattery,
        conveyor: Conveyor,
        events: SimEvents,
        physics_hz: int,
        lidar_enabled: bool = True,
        in_fleet: bool = False,
    ) -> None:
        self.lock = lock
        self.clock = clock
        self.world = world
        self.base = base
        self.holds = holds
        self.navigation = navigation
        self.scanner = scanner
        self.battery = battery
        self.conveyor = conveyor
        self.events = events
        self.control_every = max(1, physics_hz // 20)
        self.lidar_every = max(1, physics_hz // 10)
        self.lidar_enabled = lidar_enabled
        self.in_fleet = in_fleet
        self._carry = 0.0  # of sim time asked for, less than a substep not yet stepped
        self.after_step: list[Callable[[], Any]] = []  # called after each step(), outside the lock
        self.contact: str | None = None  # what the base touched in this substep
        self.collisions = 0
        self.max_penetration = 0.0
        self.motor_power = 0.0
        for other in (CT_STATIC, CT_OBSTACLE):
            world.space.on_collision(
                base.shape.collision_type, other, begin=self.on_contact, post_solve=self.on_depth
            )

    def step(self, duration: float) -> None:
        if self.in_fleet:
            raise RuntimeError("a fleet's robot is stepped by its fleet (SimFleet.step)")
        with self.lock:
            self._carry += duration
            n = int(self._carry / self.clock.dt + 1e-9)
            self._carry -= n * self.clock.dt
            before, world_step, dt = self.before_world_step, self.world.step, self.clock.dt
            for _ in range(n):  # a substep: the robot, the world, then its contacts
                before()
                world_step(dt)
                if self.contact is not None:  # after_world_step, inlined
                    self._on_collision(self.contact)
        for observe in self.after_step:  # e.g. a recorder, in fast mode
            observe()

    def run_until(
        self, predicate: Callable[[], bool], max_sim_s: float, chunk: float = 0.1
    ) -> bool:
        end = self.clock.t + max_sim_s
        while self.clock.t < end:
            if predicate():
                return True
            self.step(chunk)
        return predicate()

    def run_goal(self, max_sim_s: float = 900.0) -> GoalResult | None:
        """Step until the active goal ends (fast mode); returns its result."""
        nav = self.navigation
        self.run_until(lambda: nav.goal is None, max_sim_s)
        if nav.goal is not None:
            with self.lock:
                nav.finish("aborted", f"timed out after {max_sim_s:.0f} s")
        return nav.last_result

    def before_world_step(self) -> None:
        """The robot's share of a substep before the world moves: control, lidar, its motors."""
        clock = self.clock
        tick = clock.tick = clock.tick + 1
        dt = clock.dt
        clock.t = tick * dt
        if tick % self.control_every == 0:
            self._control(dt * self.control_every)
        if self.lidar_enabled and tick % self.lidar_every == 0:
            self.scanner.scan()
            goal = self.navigation.goal
            if goal is not None:
                self.navigation.check_path(goal)
        holds = self.holds
        self.base.ramp(dt, holds.e_stopped or holds.fault != "")

    def after_world_step(self) -> None:
        if self.contact is not None:
            self._on_collision(self.contact)

    def on_contact(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        shape = self.base.shape
        other = arbiter.shapes[1] if arbiter.shapes[0] is shape else arbiter.shapes[0]
        self.contact = getattr(other, "kind", "obstacle")

    def on_depth(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        for p in arbiter.contact_point_set.points:
            if -p.distance > self.max_penetration:
                self.max_penetration = -p.distance

    def _on_collision(self, kind: str) -> None:
        self.contact = None
        base, nav = self.base, self.navigation
        if (
            self.holds.fault
            or base.speed() < 0.05
            and nav.goal is None
            and base.teleop.until < self.clock.t
        ):
            return
        self.collisions += 1
        fault = self.holds.fault = f"collision with {kind.split(':')[0]}"
        base.target = (0.0, 0.0, 0.0)
        base.halt()
        nav.finish("aborted", fault)
        x, y, _ = base.pose
        self.events.say("fault", f"{fault} at ({x:.2f}, {y:.2f})", "error")

    # -- 20 Hz: control, battery, conveyor -----------------------------------------------
    def _control(self, dt: float) -> None:
        base, nav = self.base, self.navigation
        chassis, params = base.chassis, base.params
        goal = nav.goal
        if goal is not None:
            base.target = nav.navigate(goal)
            if chassis.differential:  # the small wheels' top speed bounds the controller
                base.target = achievable_velocity(*base.target, params)
        elif base.teleop.until >= self.clock.t:
            vx, vy, wz = base.teleop.v
            if chassis.differential:
                vy = 0.0  # no lateral motion; the wheels' limit bounds the rest
            base.target = achievable_velocity(vx, vy, wz, params)
        else:
            base.target = (0.0, 0.0, 0.0)
        base.target = nav.zone_speed(base.target)
        v = base.v
        self.motor_power = chassis.motor_power(wheel_speeds(v[0], v[1], v[2], params))
        self.battery.update(dt, self.motor_power, on_charger=nav.docked())
        done = self.conveyor.update(dt)
        if done:
            self.events.say("conveyor", f"{done}")
