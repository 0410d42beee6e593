"""Goals for the base: legs to drive, the planned path, progress and the result."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from astiop.sim.geometry import path_length


class GoalError(ValueError):
    """A goal or command was refused; the robot's state is unchanged."""


@dataclass
class Leg:
    kind: str  # navigate | dock | undock
    target: tuple[float, float, float]
    path: list[tuple[float, float]]  # waypoints after the start
    v_max: float
    planned: bool = True  # replan around obstacles (the dock legs are straight and slow)
    waypoint: int = 0
    # (path, waypoint, its segments' lengths): remaining_length's, kept while they hold
    _segments: tuple = field(default=(None, -1, ()), repr=False, compare=False)

    def remaining_length(self, x: float, y: float) -> float:
        """`path_length([(x, y)] + self.path[self.waypoint:])`, the same sum in the same order,
        the waypoints' segments measured once per path and waypoint (the control loop's 20 Hz)."""
        path, wp = self.path, self.waypoint
        held_path, held_wp, segments = self._segments
        if held_path is not path or held_wp != wp:
            segments = tuple(math.dist(p, q) for p, q in zip(path[wp:], path[wp + 1 :]))
            self._segments = (path, wp, segments)
        if wp >= len(path):
            return 0  # sum() of nothing, as path_length
        total = 0
        total += math.dist((x, y), path[wp])
        for d in segments:
            total += d
        return total


@dataclass
class Goal:
    id: int
    name: str
    legs: list[Leg]
    started_t: float
    leg: int = 0
    replans: int = 0
    blocked_since: float | None = None
    yielding_since: float | None = None  # waiting for another robot in the way
    replanned_for_robot_t: float = -math.inf
    known_boxes: list[tuple[float, float, float, float]] = field(default_factory=list)

    @property
    def current(self) -> Leg:
        return self.legs[self.leg]

    @property
    def final_pose(self) -> tuple[float, float, float]:
        return self.legs[-1].target

    def remaining_path(self, x: float, y: float) -> list[tuple[float, float]]:
        pts = [(x, y)] + self.current.path[self.current.waypoint :]
        for leg in self.legs[self.leg + 1 :]:
            pts += leg.path
        return pts

    def distance_remaining(self, x: float, y: float) -> float:
        return path_length(self.remaining_path(x, y))

    def remember(self, box: tuple[float, float, float, float]) -> None:
        cx, cy = (box[0] + box[2]) / 2, (box[1] + box[3]) / 2
        for i, k in enumerate(self.known_boxes):
            if math.hypot((k[0] + k[2]) / 2 - cx, (k[1] + k[3]) / 2 - cy) < 0.5:
                self.known_boxes[i] = (
                    min(k[0], box[0]),
                    min(k[1], box[1]),
                    max(k[2], box[2]),
                    max(k[3], box[3]),
                )
                return
        self.known_boxes.append(box)


@dataclass(frozen=True)
class GoalResult:
    id: int
    name: str
    status: str  # succeeded | aborted | canceled
    message: str
    t: float
    error_m: float
