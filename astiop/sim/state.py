"""Immutable snapshots of the simulator, safe to hand to any thread."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from astiop.sim.goal import GoalResult
from astiop.sim.perception import DetectedObstacle
from astiop.sim.world import Obstacle


@dataclass(frozen=True)
class Event:
    seq: int
    t: float
    kind: str
    severity: str
    message: str


@dataclass(frozen=True)
class SimState:
    t: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    wz: float
    wheel_speeds: tuple[float, float, float, float]
    state: str
    mode: str
    active_goal: str
    fault: str
    e_stopped: bool  # the E-STOP input; `state` reads "e_stopped" while a /stop holds too
    stop_latched: bool
    docked: bool
    battery_soc: float
    battery_voltage: float
    battery_current: float
    battery_charging: bool
    conveyor_loaded: bool
    conveyor_direction: int
    sensor_entry: bool
    sensor_seated: bool
    lamp: str
    scan_ranges: np.ndarray
    scan_stamp: float
    detected: tuple[DetectedObstacle, ...]
    plan: tuple[tuple[float, float], ...]
    distance_remaining: float
    goal_id: int
    last_result: GoalResult | None
    obstacles: tuple[Obstacle, ...]
    max_penetration: float
    collisions: int
    event_seq: int

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


def state_word(
    *,
    e_stopped: bool,
    fault: str,
    goal_kind: str | None,
    blocked: bool,
    docked: bool,
    charging: bool,
) -> str:
    """The word /robot_status reports, from the robot's condition, the gravest first."""
    if e_stopped:
        return "e_stopped"
    if fault:
        return "fault"
    if goal_kind is not None:
        if blocked:
            return "blocked"
        return "docking" if goal_kind == "dock" else "navigating"
    if docked:
        return "charging" if charging else "idle"
    return "idle"


def lamp(state: str, conveyor_running: bool, speed: float, goal) -> str:
    """The signal lamp's colour for a state word."""
    if state in ("e_stopped", "fault"):
        return "red"
    if state == "blocked" or conveyor_running:
        return "yellow"
    if state == "charging":
        return "blue"
    return "green_flashing" if speed > 0.01 or goal else "green"
