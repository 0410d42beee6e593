"""Goto-pose control: drive the tracking error of Eq. 8 to zero along a planned path.

The base is holonomic, so translation and rotation are controlled independently in the robot
frame: the error e = R(θ)ᵀ (x_d − x) gives the direction to move in directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from astiop.sim.geometry import wrap_angle


@dataclass(frozen=True)
class ControllerGains:
    v_max: float = 0.8  # m/s
    w_max: float = 0.8  # rad/s
    a_max: float = 0.6  # m/s², the deceleration the profile plans with
    k_heading: float = 1.5
    k_position: float = 1.2
    waypoint_radius: float = 0.35  # m, switch to the next waypoint when this close
    goal_tolerance: float = 0.03  # m
    heading_tolerance: float = math.radians(2.0)


def tracking_error(pose, goal) -> tuple[float, float, float]:
    """Eq. 8: the goal (x_d, y_d, θ_d) expressed in the robot frame."""
    x, y, th = pose
    xd, yd, thd = goal
    c, s = math.cos(th), math.sin(th)
    dx, dy = xd - x, yd - y
    return (c * dx + s * dy, -s * dx + c * dy, wrap_angle(thd - th))


def goto_pose_command(
    pose, target_xy, goal_theta: float, remaining: float, final: bool, gains: ControllerGains
) -> tuple[float, float, float]:
    """Body velocity (vx, vy, wz) toward `target_xy` with the path's `remaining` length ahead."""
    ex, ey, eth = tracking_error(pose, (target_xy[0], target_xy[1], goal_theta))
    dist = math.hypot(ex, ey)
    # trapezoidal profile: slow down so the robot can stop at the end of the path
    speed = min(gains.v_max, math.sqrt(2.0 * gains.a_max * max(remaining, 0.0)))
    if final:
        speed = min(speed, gains.k_position * dist)
    if dist > 1e-9:
        vx, vy = speed * ex / dist, speed * ey / dist
    else:
        vx = vy = 0.0
    wz = max(-gains.w_max, min(gains.w_max, gains.k_heading * eth))
    return vx, vy, wz


def arrived(pose, goal, gains: ControllerGains) -> bool:
    ex, ey, eth = tracking_error(pose, goal)
    return math.hypot(ex, ey) <= gains.goal_tolerance and abs(eth) <= gains.heading_tolerance


def diff_drive_command(
    pose, target_xy, goal_theta: float, remaining: float, final: bool, gains: ControllerGains
) -> tuple[float, float, float]:
    """(v, 0, ω) toward `target_xy` for a base that cannot move sideways: turn toward the point,
    drive while roughly facing it; within the goal tolerance of the last point, turn in place to
    the goal's heading (a stateful goal checker: the position once reached is kept)."""
    ex, ey, eth = tracking_error(pose, (target_xy[0], target_xy[1], goal_theta))
    dist = math.hypot(ex, ey)
    if final and dist <= gains.goal_tolerance:
        return 0.0, 0.0, max(-gains.w_max, min(gains.w_max, gains.k_heading * eth))
    bearing = math.atan2(ey, ex)
    speed = min(gains.v_max, math.sqrt(2.0 * gains.a_max * max(remaining, 0.0)))
    if final:
        speed = min(speed, gains.k_position * dist)
    v = 0.0 if abs(bearing) > math.pi / 4 else speed * math.cos(bearing)
    wz = max(-gains.w_max, min(gains.w_max, 2.0 * gains.k_heading * bearing))
    return v, 0.0, wz
