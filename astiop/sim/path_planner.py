"""Global planning: a visibility graph over the inflated obstacles, grid A* as the fallback.

Obstacles are axis-aligned boxes grown by the robot's circumscribed radius, so any heading is
safe along the path. The graph over the fixed map's box corners is built once; a query adds the
start, the goal and any detected obstacles, then runs A* over a few hundred nodes.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass

import numpy as np

from astiop.sim.geometry import inflate, path_length, points_in_boxes, segments_hit_boxes
from astiop.sim.keepout import Keepout

NODE_OFFSET = 0.02


class PlanningError(Exception):
    """No collision-free path exists."""


@dataclass(frozen=True)
class Plan:
    waypoints: tuple[tuple[float, float], ...]  # start first, goal last
    length: float
    ms: float
    method: str


def _corners(boxes: np.ndarray, offset: float) -> np.ndarray:
    b = inflate(boxes, offset)
    return (
        np.concatenate([b[:, [0, 1]], b[:, [2, 1]], b[:, [2, 3]], b[:, [0, 3]]])
        if len(b)
        else np.zeros((0, 2))
    )


class PathPlanner:
    def __init__(
        self,
        static_boxes: np.ndarray,
        bounds,
        inflation: float = 0.72,
        grid_resolution: float = 0.1,
    ):
        self.inflation = inflation
        self.bounds = bounds
        self.grid_resolution = grid_resolution
        self.boxes = inflate(np.asarray(static_boxes, dtype=float), inflation)
        nodes = _corners(self.boxes, NODE_OFFSET)
        nodes = nodes[self._free(nodes, self.boxes)]
        self.nodes = nodes
        n = len(nodes)
        i, j = np.triu_indices(n, k=1)
        blocked = segments_hit_boxes(nodes[i], nodes[j], self.boxes).any(axis=1)
        self._pairs_i, self._pairs_j = i[~blocked], j[~blocked]
        self.set_keepout(())

    def set_keepout(self, polygons, margin: float = 0.0) -> None:
        """Keepout zones no plan may cross (nor pass closer than `margin` to)."""
        key = (tuple(tuple(map(tuple, p)) for p in polygons), margin)
        if getattr(self, "_keepout_key", None) == key:
            return
        self._keepout_key = key
        self.keepout = Keepout(polygons, margin)
        if not self.keepout:
            self._keepout_free = np.ones(len(self.nodes), dtype=bool)
            self._keepout_pairs = np.ones(len(self._pairs_i), dtype=bool)
            return
        self._keepout_free = self.keepout.status(self.nodes).max(axis=1) == 0
        self._keepout_pairs = ~self.keepout.blocks(
            self.nodes[self._pairs_i], self.nodes[self._pairs_j]
        )

    def _free(self, points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        x0, y0, x1, y1 = self.bounds
        inside = (
            (points[:, 0] > x0) & (points[:, 0] < x1) & (points[:, 1] > y0) & (points[:, 1] < y1)
        )
        return inside & ~points_in_boxes(points, boxes).any(axis=1)

    def plan(self, start, goal, extra_boxes=(), method: str = "auto") -> Plan:
        t0 = time.perf_counter()
        extra = inflate(np.asarray(extra_boxes, dtype=float).reshape(-1, 4), self.inflation)
        start, goal = (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))
        if method in ("auto", "visibility"):
            try:
                pts = self._visibility(start, goal, extra)
                return Plan(
                    tuple(pts), path_length(pts), (time.perf_counter() - t0) * 1e3, "visibility"
                )
            except PlanningError:
                if method == "visibility":
                    raise
        pts = self._grid(start, goal, extra)
        return Plan(tuple(pts), path_length(pts), (time.perf_counter() - t0) * 1e3, "grid")

    # -- visibility graph ------------------------------------------------------------
    def _visibility(self, start, goal, extra: np.ndarray) -> list[tuple[float, float]]:
        all_boxes = np.concatenate([self.boxes, extra]) if len(extra) else self.boxes
        ends = np.array([start, goal])
        # boxes that contain the start (or goal) are ignored on edges leaving it
        inside = points_in_boxes(ends, all_boxes)
        static_nodes = self.nodes
        extra_nodes = np.concatenate([_corners(extra, NODE_OFFSET), self.keepout.nodes])
        if len(extra_nodes):
            extra_nodes = extra_nodes[self._free(extra_nodes, all_boxes)]
        if len(extra):
            keep_static = ~points_in_boxes(static_nodes, extra).any(axis=1)
        else:
            keep_static = np.ones(len(static_nodes), dtype=bool)
        keep_static = keep_static & self._keepout_free
        nodes = np.concatenate([static_nodes, extra_nodes, ends])
        n_static, n = len(static_nodes), len(static_nodes) + len(extra_nodes) + 2
        s_idx, g_idx = n - 2, n - 1
        edges_i, edges_j = [], []
        # cached static pairs, minus those cut by new obstacles
        pi, pj = self._pairs_i, self._pairs_j
        ok = keep_static[pi] & keep_static[pj] & self._keepout_pairs
        if len(extra):
            ok &= ~segments_hit_boxes(static_nodes[pi], static_nodes[pj], extra).any(axis=1)
        edges_i.append(pi[ok])
        edges_j.append(pj[ok])
        # pairs with a new node
        new = np.arange(n_static, n)
        ii, jj = np.meshgrid(new, np.arange(n), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        mask = (ii != jj) & ((jj < n_static) | (jj > ii))
        mask &= np.concatenate([keep_static, np.ones(n - n_static, dtype=bool)])[jj]
        ii, jj = ii[mask], jj[mask]
        hits = segments_hit_boxes(nodes[ii], nodes[jj], all_boxes)
        for end, row in ((s_idx, 0), (g_idx, 1)):
            touches = (ii == end) | (jj == end)
            hits[touches] &= ~inside[row]
        both = ((ii == s_idx) & (jj == g_idx)) | ((ii == g_idx) & (jj == s_idx))
        hits[both] &= ~(inside[0] | inside[1])
        free = ~hits.any(axis=1)
        if self.keepout:
            status = self.keepout.status(ends)
            relax = self.keepout.relax_for(ii, jj, {s_idx: status[0], g_idx: status[1]})
            free[free] = ~self.keepout.blocks(nodes[ii[free]], nodes[jj[free]], relax[free])
        edges_i.append(ii[free])
        edges_j.append(jj[free])
        ei, ej = np.concatenate(edges_i), np.concatenate(edges_j)
        w = np.hypot(*(nodes[ei] - nodes[ej]).T)
        adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
        for a, b, d in zip(ei.tolist(), ej.tolist(), w.tolist()):
            adj[a].append((b, d))
            adj[b].append((a, d))
        route = _astar(adj, nodes, s_idx, g_idx)
        if route is None:
            raise PlanningError("no collision-free path")
        return [tuple(map(float, nodes[k])) for k in route]

    # -- grid A* with line-of-sight smoothing --------------------------------------
    def _grid(self, start, goal, extra: np.ndarray) -> list[tuple[float, float]]:
        res = self.grid_resolution
        x0, y0, x1, y1 = self.bounds
        nx, ny = int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))
        boxes = np.concatenate([self.boxes, extra]) if len(extra) else self.boxes
        ends = np.array([start, goal])
        containing = points_in_boxes(ends, boxes).any(axis=0)
        occ = np.zeros((nx, ny), dtype=bool)
        for k, (bx0, by0, bx1, by1) in enumerate(boxes):
            if containing[k]:
                continue  # the robot is already in it: let it leave / arrive
            i0, i1 = int((bx0 - x0) / res), int(math.ceil((bx1 - x0) / res))
            j0, j1 = int((by0 - y0) / res), int(math.ceil((by1 - y0) / res))
            occ[max(i0, 0) : max(i1, 0), max(j0, 0) : max(j1, 0)] = True

        if self.keepout:
            cx = x0 + (np.arange(nx) + 0.5) * res
            cy = y0 + (np.arange(ny) + 0.5) * res
            gx, gy = np.meshgrid(cx, cy, indexing="ij")
            occ |= self.keepout.occupied(gx, gy, self.keepout.status(ends))

        def cell(p):
            return (
                min(max(int((p[0] - x0) / res), 0), nx - 1),
                min(max(int((p[1] - y0) / res), 0), ny - 1),
            )

        s, g = cell(start), cell(goal)
        if occ[g]:
            raise PlanningError("the goal is inside an obstacle's safety margin")
        occ[s] = False
        came: dict = {s: None}
        cost = {s: 0.0}
        heap = [(0.0, s)]
        steps = [
            (1, 0, 1.0),
            (-1, 0, 1.0),
            (0, 1, 1.0),
            (0, -1, 1.0),
            (1, 1, 1.414),
            (1, -1, 1.414),
            (-1, 1, 1.414),
            (-1, -1, 1.414),
        ]
        while heap:
            _, cur = heapq.heappop(heap)
            if cur == g:
                break
            for di, dj, dc in steps:
                nb = (cur[0] + di, cur[1] + dj)
                if not (0 <= nb[0] < nx and 0 <= nb[1] < ny) or occ[nb]:
                    continue
                c = cost[cur] + dc
                if c < cost.get(nb, math.inf):
                    cost[nb] = c
                    came[nb] = cur
                    heapq.heappush(heap, (c + math.hypot(g[0] - nb[0], g[1] - nb[1]), nb))
        if g not in came:
            raise PlanningError("no collision-free path")
        cells = []
        cur = g
        while cur is not None:
            cells.append(cur)
            cur = came[cur]
        cells.reverse()
        pts = [start] + [(x0 + (i + 0.5) * res, y0 + (j + 0.5) * res) for i, j in cells[1:-1]]
        pts.append(goal)
        return self._smooth(pts, boxes[~containing])

    def _smooth(self, pts, boxes: np.ndarray):
        out = [pts[0]]
        i = 0
        ends = self.keepout.status(np.array([pts[0], pts[-1]])) if self.keepout else None
        while i < len(pts) - 1:
            j = len(pts) - 1
            while j > i + 1:
                a, b = np.array([pts[i]]), np.array([pts[j]])
                seg = segments_hit_boxes(a, b, boxes)
                if not seg.any() and ends is not None:
                    let_off = {0: ends[0], len(pts) - 1: ends[1]}
                    relax = self.keepout.relax_for(np.array([i]), np.array([j]), let_off)
                    seg = self.keepout.blocks(a, b, relax)
                if not seg.any():
                    break
                j -= 1
            out.append(pts[j])
            i = j
        return out


def _astar(adj, nodes: np.ndarray, start: int, goal: int) -> list[int] | None:
    gx, gy = nodes[goal]
    h = np.hypot(nodes[:, 0] - gx, nodes[:, 1] - gy).tolist()
    best = {start: 0.0}
    came = {start: -1}
    heap = [(h[start], start)]
    closed = set()
    while heap:
        _, cur = heapq.heappop(heap)
        if cur == goal:
            route = [cur]
            while came[route[-1]] != -1:
                route.append(came[route[-1]])
            return route[::-1]
        if cur in closed:
            continue
        closed.add(cur)
        for nb, d in adj[cur]:
            c = best[cur] + d
            if c < best.get(nb, math.inf):
                best[nb] = c
                came[nb] = cur
                heapq.heappush(heap, (c + h[nb], nb))
    return None
