"""The map view's pure arithmetic: a robot's body as points, changed lines as runs, where each
pixel's centre is in metres."""

from __future__ import annotations

import math

import numpy as np


def body_points(x: float, y: float, th: float, length: float = 1.0, width: float = 0.735):
    c, s = math.cos(th), math.sin(th)
    u = np.linspace(-length / 2, length / 2, 6)
    v = np.linspace(-width / 2, width / 2, 5)
    gu, gv = (a.ravel() for a in np.meshgrid(u, v))
    return x + gu * c - gv * s, y + gu * s + gv * c


def line_runs(lines: np.ndarray) -> list[tuple[int, int]]:
    """Sorted line numbers (repeats allowed) as runs of consecutive lines: (first, count)."""
    runs: list[tuple[int, int]] = []
    for y in np.unique(lines).tolist():
        if runs and runs[-1][0] + runs[-1][1] == y:
            runs[-1] = (runs[-1][0], runs[-1][1] + 1)
        else:
            runs.append((y, 1))
    return runs


def pixel_centres(shape: tuple[int, int], s: float, x0: float, y0: float, top: int):
    """(x, y) in metres of each pixel's centre: `s` pixels a metre, row `top - 1` at y0."""
    rows, cols = np.arange(shape[0]), np.arange(shape[1])
    return np.meshgrid(x0 + (cols + 0.5) / s, y0 + (top - rows - 0.5) / s)


# -- drawing into a view's pixels through its frame (map_viewport.Frame: s, x0, y0, top) --------
def fill_rect(px: np.ndarray, rect, value: int, frame) -> None:
    s, x0, y0, top = frame
    c0 = int(math.floor((rect[0] - x0) * s))
    c1 = int(math.ceil((rect[2] - x0) * s))
    r0 = top - int(math.ceil((rect[3] - y0) * s))
    r1 = top - int(math.floor((rect[1] - y0) * s))
    px[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = value


def plot(px: np.ndarray, xs, ys, value: int, frame) -> None:
    s, x0, y0, top = frame
    full_h, w = px.shape
    cols = np.floor((np.asarray(xs, dtype=float) - x0) * s).astype(int)
    rows = top - 1 - np.floor((np.asarray(ys, dtype=float) - y0) * s).astype(int)
    ok = (cols >= 0) & (cols < w) & (rows >= 0) & (rows < full_h)
    px[rows[ok], cols[ok]] = value


def polyline(px: np.ndarray, points, value: int, frame) -> None:
    """Each segment drawn with two samples a pixel."""
    for (ax, ay), (bx, by) in zip(points, points[1:]):
        n = max(int(math.dist((ax, ay), (bx, by)) * frame[0] * 2), 2)
        plot(px, np.linspace(ax, bx, n), np.linspace(ay, by, n), value, frame)


def fill_polygons(px: np.ndarray, polygons, frame, inside) -> None:
    """Each pixel whose centre is inside a polygon, in its value: (corners, value) in order,
    the later over the earlier; `inside(xs, ys, corners)` is the test over arrays."""
    gx, gy = pixel_centres(px.shape, frame[0], frame[1], frame[2], frame[3])
    for corners, value in polygons:
        px[inside(gx, gy, corners)] = value
