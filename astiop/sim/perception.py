"""The obstacle detector: clusters of scan points that are not the fixed map.

The simulator knows which edge each beam hit, which stands in for the map comparison a real
detector does; clustering, size, kind and bearing come from the scan points alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CLUSTER_GAP_M = 0.35


@dataclass(frozen=True)
class DetectedObstacle:
    kind: str
    distance: float  # m, nearest point
    bearing: float  # rad, robot frame, of the nearest point
    x: float  # map frame, cluster centre
    y: float
    size: float  # m, largest extent of the points
    bbox: tuple[float, float, float, float]  # map frame, of the points seen
    robot: int = -1  # which robot of the world it is (its rank), for kind "robot"


def classify(size: float) -> str:
    if size <= 0.75:
        return "person"
    if size <= 1.6:
        return "pallet"
    if size <= 3.0:
        return "forklift"
    return "unknown"


def detect(
    ranges: np.ndarray,
    unmapped: np.ndarray,
    angles: np.ndarray,
    pose: tuple[float, float, float],
    robots: np.ndarray | None = None,
) -> list[DetectedObstacle]:
    """`unmapped[i]` is true where beam i hit something that is not on the map; `robots[i]` is
    the rank of the robot beam i hit, or -1 (a fleet's robots know one another: kind "robot")."""
    n = len(ranges)
    beams = np.nonzero(unmapped & np.isfinite(ranges))[0]
    if len(beams) == 0:
        return []
    x, y, theta = pose
    world_angles = theta + angles[beams]
    px = x + ranges[beams] * np.cos(world_angles)
    py = y + ranges[beams] * np.sin(world_angles)
    # split where beams are not adjacent or points are far apart
    breaks = [0]
    for i in range(1, len(beams)):
        gap = math.hypot(px[i] - px[i - 1], py[i] - py[i - 1])
        if beams[i] - beams[i - 1] > 2 or gap > CLUSTER_GAP_M:
            breaks.append(i)
    groups = [list(range(s, e)) for s, e in zip(breaks, breaks[1:] + [len(beams)])]
    # the scan wraps around at the back of the robot
    if len(groups) > 1 and beams[0] == 0 and beams[-1] == n - 1:
        first, last = groups[0], groups[-1]
        if math.hypot(px[first[0]] - px[last[-1]], py[first[0]] - py[last[-1]]) <= CLUSTER_GAP_M:
            groups = [last + first] + groups[1:-1]
    found = []
    for g in groups:
        gx, gy = px[g], py[g]
        size = max(float(np.hypot(gx[:, None] - gx, gy[:, None] - gy).max()), 0.1)
        nearest = g[int(np.argmin(ranges[beams[g]]))]
        ranks = robots[beams[g]] if robots is not None else np.array([-1])
        robot = int(np.bincount(ranks[ranks >= 0]).argmax()) if (ranks >= 0).mean() > 0.5 else -1
        found.append(
            DetectedObstacle(
                kind="robot" if robot >= 0 else classify(size),
                distance=float(ranges[beams[nearest]]),
                bearing=float(angles[beams[nearest]]),
                x=float(gx.mean()),
                y=float(gy.mean()),
                size=size,
                bbox=(float(gx.min()), float(gy.min()), float(gx.max()), float(gy.max())),
                robot=robot,
            )
        )
    found.sort(key=lambda o: o.distance)
    return found
