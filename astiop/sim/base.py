"""The robot's base in the world: its pymunk bodies, its pose, and its motors' velocity, ramped
each physics step toward the one commanded (by a goal or by teleop)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pymunk

from astiop.sim.body import Body
from astiop.sim.geometry import wrap_angle
from astiop.sim.kinematics import MecanumParams
from astiop.sim.world import World

A_LIN, A_ANG = 1.0, 2.0  # m/s², rad/s² the base ramps with
# the properties' own setters (pymunk.Body's __setattr__ hook doubles their cost)
_SET_VELOCITY = pymunk.Body.velocity.fset  # type: ignore[attr-defined]
_SET_ANGULAR_VELOCITY = pymunk.Body.angular_velocity.fset  # type: ignore[attr-defined]

Velocity = tuple[float, float, float]  # vx, vy, wz
Pose = tuple[float, float, float]  # x, y, theta


@dataclass
class Teleop:
    v: Velocity = (0.0, 0.0, 0.0)
    until: float = -1.0  # sim time it lapses at


class Base:
    """Added to `world` at `pose` on construction; `owner` is what the world knows it by (the
    simulator: its name, and its goal for the others' right of way)."""

    def __init__(
        self, world: World, pose: Pose, chassis: Body, params: MecanumParams, owner: object
    ) -> None:
        self.world = world
        self.chassis = chassis
        self.params = params
        self.control, self.body, self.shape = world.add_robot(
            pose, chassis.mass, chassis.length, chassis.width, owner
        )
        self.v = [0.0, 0.0, 0.0]  # the velocity reached (robot frame), floats: per step
        self.target: Velocity = (0.0, 0.0, 0.0)  # the velocity commanded, `v` ramps toward it
        self.applied: Velocity = (0.0, 0.0, 0.0)  # the control body's (map frame), as last set
        self.teleop = Teleop()
        self._pose_at: tuple[int, Pose] = (-1, (0.0, 0.0, 0.0))  # (world step, pose)

    @property
    def pose(self) -> Pose:
        step, pose = self._pose_at
        if step != self.world.steps:  # read once per physics step, not per use
            p = self.body.position
            pose = (p.x, p.y, wrap_angle(self.body.angle))
            self._pose_at = (self.world.steps, pose)
        return pose

    def speed(self) -> float:
        return float(math.hypot(self.v[0], self.v[1]))

    def halt(self) -> None:
        """At rest at once (an E-STOP, a collision): teleop dropped, the motors stopped."""
        self.teleop = Teleop()
        self.v[:] = (0.0, 0.0, 0.0)
        self.control.velocity, self.control.angular_velocity = (0, 0), 0.0
        self.applied = (0.0, 0.0, 0.0)

    def ramp(self, dt: float, halted: bool) -> None:
        """One physics step of the motors: `v` toward `target` (to rest at once if `halted`),
        set on the control body in the map frame. 100 Hz: written for speed
        (min(d, max(-d, x)) spelled as comparisons, same values)."""
        v = self.v
        if halted:
            v[:] = vx, vy, wz = (0.0, 0.0, 0.0)
        else:
            tx, ty, tw = self.target
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
        applied = self.applied
        if command != applied:  # pymunk's attribute setters cost more than the check
            self.applied = command
            # setting a kinematic body's velocity to the value it has is no change: skipped
            if command[:2] != applied[:2]:
                _SET_VELOCITY(self.control, command[:2])
            if wz != applied[2]:
                _SET_ANGULAR_VELOCITY(self.control, wz)
