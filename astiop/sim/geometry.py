"""Vectorised 2D geometry shared by the lidar, the planner and the obstacle detector."""

from __future__ import annotations

import math

import numpy as np

Rect = tuple[float, float, float, float]


def wrap_angle(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def rect_edges(rect: Rect) -> tuple[np.ndarray, np.ndarray]:
    """Edges of an axis-aligned rectangle, counter-clockwise (outward normal = (dy, -dx))."""
    x0, y0, x1, y1 = rect
    pts = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)
    return pts, np.roll(pts, -1, axis=0)


def polygon_edges(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges of a counter-clockwise polygon."""
    return vertices, np.roll(vertices, -1, axis=0)


def oriented_box(cx: float, cy: float, theta: float, length: float, width: float) -> np.ndarray:
    """Counter-clockwise corners of a box centred at (cx, cy) with heading theta."""
    c, s = math.cos(theta), math.sin(theta)
    hl, hw = length / 2, width / 2
    local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
    return local @ np.array([[c, s], [-s, c]]) + np.array([cx, cy])


def circle_polygon(cx: float, cy: float, radius: float, n: int = 12) -> np.ndarray:
    a = np.linspace(0, 2 * math.pi, n, endpoint=False)
    # circumscribed so the polygon never reads shorter than the circle
    r = radius / math.cos(math.pi / n)
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def segments_hit_boxes(p0: np.ndarray, p1: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(M, K) bool: does segment m pass through the open interior of box k (Liang-Barsky)."""
    if len(boxes) == 0 or len(p0) == 0:
        return np.zeros((len(p0), len(boxes)), dtype=bool)
    eps = 1e-7
    x0 = p0[:, 0:1]
    y0 = p0[:, 1:2]
    dx = (p1[:, 0] - p0[:, 0])[:, None]
    dy = (p1[:, 1] - p0[:, 1])[:, None]
    bx0, by0 = boxes[:, 0] + eps, boxes[:, 1] + eps
    bx1, by1 = boxes[:, 2] - eps, boxes[:, 3] - eps
    t0 = np.zeros((len(p0), len(boxes)))
    t1 = np.ones((len(p0), len(boxes)))
    hit = np.ones((len(p0), len(boxes)), dtype=bool)
    for p, q in ((-dx, x0 - bx0), (dx, bx1 - x0), (-dy, y0 - by0), (dy, by1 - y0)):
        p = np.broadcast_to(p, t0.shape)
        q = np.broadcast_to(q, t0.shape)
        parallel = np.abs(p) < 1e-12
        hit &= ~(parallel & (q < 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(parallel, 0.0, q / np.where(parallel, 1.0, p))
        entering = (p < 0) & ~parallel
        leaving = (p > 0) & ~parallel
        t0 = np.where(entering, np.maximum(t0, r), t0)
        t1 = np.where(leaving, np.minimum(t1, r), t1)
    return hit & (t0 < t1)


def points_in_boxes(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(N, K) bool: is point n strictly inside box k."""
    if len(boxes) == 0:
        return np.zeros((len(points), 0), dtype=bool)
    x = points[:, 0:1]
    y = points[:, 1:2]
    return (x > boxes[:, 0]) & (x < boxes[:, 2]) & (y > boxes[:, 1]) & (y < boxes[:, 3])


def inflate(boxes: np.ndarray, margin: float) -> np.ndarray:
    return boxes + np.array([-margin, -margin, margin, margin])


def path_length(points) -> float:
    return sum(math.dist(p, q) for p, q in zip(points, points[1:]))
