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
    gaps = np.hypot(np.diff(px), np.diff(py))
    breaks = [0, *(np.nonzero((np.diff(beams) > 2) | (gaps > CLUSTER_GAP_M))[0] + 1).tolist()]
    groups = [list(range(s, e)) for s, e in zip(breaks, breaks[1:] + [len(beams)])]
    # the scan wraps around at the back of the robot
    if len(groups) > 1 and beams[0] == 0 and beams[-1] == n - 1:
        first, last = groups[0], groups[-1]
        if math.hypot(px[first[0]] - px[last[-1]], py[first[0]] - py[last[-1]]) <= CLUSTER_GAP_M:
            groups = [last + first] + groups[1:-1]
    order = np.concatenate([np.asarray(g, dtype=np.int64) for g in groups])
    counts = np.array([len(g) for g in groups])
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    gx, gy, r = px[order], py[order], ranges[beams[order]]
    group = np.repeat(np.arange(len(groups)), counts)
    # per group at once: the nearest point (lexsort: by group, then range), centre, bbox
    nearest = order[np.lexsort((r, group))[starts]]
    cx, cy = np.add.reduceat(gx, starts) / counts, np.add.reduceat(gy, starts) / counts
    x0, x1 = np.minimum.reduceat(gx, starts), np.maximum.reduceat(gx, starts)
    y0, y1 = np.minimum.reduceat(gy, starts), np.maximum.reduceat(gy, starts)
    ranks = robots[beams[order]] if robots is not None else np.full(len(order), -1)
    found = []
    for k, (s, c) in enumerate(zip(starts.tolist(), counts.tolist(), strict=True)):
        px_k, py_k = gx[s : s + c], gy[s : s + c]
        size = max(float(np.hypot(px_k[:, None] - px_k, py_k[:, None] - py_k).max()), 0.1)
        rk = ranks[s : s + c]
        robot = int(np.bincount(rk[rk >= 0]).argmax()) if (rk >= 0).sum() * 2 > c else -1
        found.append(
            DetectedObstacle(
                kind="robot" if robot >= 0 else classify(size),
                distance=float(ranges[beams[nearest[k]]]),
                bearing=float(angles[beams[nearest[k]]]),
                x=float(cx[k]),
                y=float(cy[k]),
                size=size,
                bbox=(float(x0[k]), float(y0[k]), float(x1[k]), float(y1[k])),
                robot=robot,
            )
        )
    found.sort(key=lambda o: o.distance)
    return found
