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
