"""Keepout zones in the planner: polygons no path may cross or pass closer than a margin to.

The visibility graph gains nodes around each zone's corners; a segment is blocked by a zone
when it comes within the margin of it. The start and the goal are let off as the planner lets
them off a box they stand in: a robot inside a zone (one drawn around it) may leave it, and one
within the margin may set off or arrive, though never through the zone itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from astiop.zones import points_in_polygon, segments_polygon_distance

CLEAR, NEAR, INSIDE = 0, 1, 2
# nodes are placed this much beyond the margin, in 8 directions around each corner: the chord
# between two neighbours passes at cos(22.5°) of their distance from the corner
NODE_REACH = 1.0 / np.cos(np.pi / 8) + 0.05


class Keepout:
    def __init__(self, polygons: Sequence[Sequence[tuple[float, float]]], margin: float):
        self.polygons = [np.asarray(p, dtype=float) for p in polygons]
        self.margin = margin
        angles = np.arange(8) * np.pi / 4
        ring = np.stack([np.cos(angles), np.sin(angles)], axis=1) * margin * NODE_REACH
        nodes = [c + ring for poly in self.polygons for c in poly]
        nodes = np.concatenate(nodes) if nodes else np.zeros((0, 2))
        self.nodes = nodes[self.status(nodes).max(axis=1, initial=CLEAR) == CLEAR]

    def __bool__(self) -> bool:
        return bool(self.polygons)

    def status(self, points: np.ndarray) -> np.ndarray:
        """(points, polygons): CLEAR, NEAR (within the margin) or INSIDE."""
        out = np.zeros((len(points), len(self.polygons)), dtype=int)
        for k, poly in enumerate(self.polygons):
            d = segments_polygon_distance(points, points, poly)
            inside = points_in_polygon(points[:, 0], points[:, 1], poly)
            out[:, k] = np.where(inside, INSIDE, np.where(d < self.margin, NEAR, CLEAR))
        return out

    def blocks(self, p: np.ndarray, q: np.ndarray, relax: np.ndarray | None = None) -> np.ndarray:
        """Which segments p[i]-q[i] a zone blocks; `relax` (segments, polygons): how far an end
        of each segment is let off (NEAR: only crossing blocks; INSIDE: nothing does)."""
        blocked = np.zeros(len(p), dtype=bool)
        if not len(p):
            return blocked
        for k, poly in enumerate(self.polygons):
            r = relax[:, k] if relax is not None else np.zeros(len(p), dtype=int)
            d = segments_polygon_distance(p, q, poly)
            blocked |= np.where(r == CLEAR, d < self.margin, (r == NEAR) & (d <= 0.0))
        return blocked

    def relax_for(self, ii: np.ndarray, jj: np.ndarray, ends: dict[int, np.ndarray]):
        """The let-off of segments between node indices ii, jj, given each end node's status."""
        relax = np.zeros((len(ii), len(self.polygons)), dtype=int)
        for index, status in ends.items():
            touches = (ii == index) | (jj == index)
            relax[touches] = np.maximum(relax[touches], status)
        return relax

    def occupied(self, xs: np.ndarray, ys: np.ndarray, ends_status: np.ndarray) -> np.ndarray:
        """Grid cells (centres xs, ys) a zone covers, its margin included unless an end stands
        in it (then the zone alone, or nothing if an end is inside)."""
        occ = np.zeros(xs.shape, dtype=bool)
        for k, poly in enumerate(self.polygons):
            worst = ends_status[:, k].max(initial=CLEAR)
            if worst == INSIDE:
                continue
            margin = self.margin if worst == CLEAR else 0.0
            x0, y0 = poly.min(axis=0) - margin
            x1, y1 = poly.max(axis=0) + margin
            near = (xs >= x0) & (xs <= x1) & (ys >= y0) & (ys <= y1)
            pts = np.stack([xs[near], ys[near]], axis=1)
            d = segments_polygon_distance(pts, pts, poly)
            occ[near] |= d <= margin if margin == 0.0 else d < margin
        return occ
