"""Where the map view looks, and what a terminal cell is in metres: pure arithmetic, no Textual.

A `Frame` maps metres to the view's pixels (two pixels a cell, one above the other): `s` pixels a
metre, pixel column 0's left edge at x0, the bottom edge of pixel row `top - 1` at y0. The
`Viewport` owns zoom and pan and makes the frame for a view's size; at zoom 1 with no pan it
fits the whole map (left-aligned, centred vertically). `pick` says what a cell points at.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

Bounds = tuple[float, float, float, float]  # x0, y0, x1, y1 in metres

MIN_ZOOM, MAX_ZOOM = 0.5, 32.0
ZOOM_STEP = 1.5
ROBOT_RADIUS_M = 0.6  # a click this close to a robot's centre is on the robot


class Frame(NamedTuple):
    s: float  # pixels a metre
    x0: float
    y0: float
    top: int

    def cell_box(self, col: int, row: int) -> Bounds:
        """The metres a terminal cell covers: (x0, y0, x1, y1)."""
        xa = self.x0 + col / self.s
        yb = self.y0 + (self.top - 2 * row) / self.s
        return xa, yb - 2 / self.s, xa + 1 / self.s, yb

    def cell_centre(self, col: int, row: int) -> tuple[float, float]:
        xa, ya, xb, yb = self.cell_box(col, row)
        return (xa + xb) / 2, (ya + yb) / 2

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """The (column, row) of the cell that holds the point."""
        return math.floor((x - self.x0) * self.s), (
            self.top - 1 - math.floor((y - self.y0) * self.s)
        ) // 2


class Pick(NamedTuple):
    """What a cell points at: its centre in metres, and the robot there, if any."""

    x: float
    y: float
    robot: str | None = None


def pick(frame: Frame, col: int, row: int, robots: list[tuple[str, float, float]]) -> Pick:
    """The point at the cell's centre; a robot (name, x, y) whose body overlaps the cell is
    picked instead, the nearest if several do."""
    x, y = frame.cell_centre(col, row)
    xa, ya, xb, yb = frame.cell_box(col, row)
    best: tuple[float, str] | None = None
    for name, rx, ry in robots:
        # the distance from the robot's centre to the cell's box
        d = math.hypot(max(xa - rx, 0.0, rx - xb), max(ya - ry, 0.0, ry - yb))
        if d <= ROBOT_RADIUS_M and (best is None or d < best[0]):
            best = (d, name)
    return Pick(x, y, best[1] if best else None)


@dataclass
class Viewport:
    zoom: float = 1.0
    pan_x: float = 0.0  # metres the view's centre is moved from the fitted view's
    pan_y: float = 0.0

    @property
    def fitted(self) -> bool:
        return self.zoom == 1.0 and self.pan_x == 0.0 and self.pan_y == 0.0

    def fit(self) -> None:
        self.zoom, self.pan_x, self.pan_y = 1.0, 0.0, 0.0

    @staticmethod
    def _fit(w: int, h: int, bounds: Bounds) -> Frame:
        x0, y0, x1, y1 = bounds
        # metres stay square: a cell is twice as tall as wide, two pixels per cell vertically
        s = max(min(w / (x1 - x0), h / (y1 - y0)), 1e-6)  # a view not laid out yet: tiny
        map_h = int(math.ceil((y1 - y0) * s))
        return Frame(s, x0, y0, h - max((h - map_h) // 2, 0))

    def _centre(self, fit: Frame, w: int, h: int) -> tuple[float, float]:
        fx, fy = self._fit_centre(fit, w, h)
        return fx + self.pan_x, fy + self.pan_y

    def frame(self, w: int, h: int, bounds: Bounds) -> Frame:
        """The frame for a view of w x h pixels over a map of these bounds."""
        fit = self._fit(w, h, bounds)
        if self.fitted:
            return fit  # exactly as before zoom existed
        cx, cy = self._centre(fit, w, h)
        s = fit.s * self.zoom
        return Frame(s, cx - w / (2 * s), cy - (fit.top - h / 2) / s, fit.top)

    def zoom_by(
        self, factor: float, w: int, h: int, bounds: Bounds, about: tuple[float, float] | None
    ) -> None:
        """Zoom in (factor > 1) or out, the point `about` (metres) staying where it is on the
        screen; None: the view's centre."""
        fit = self._fit(w, h, bounds)
        cx, cy = self._centre(fit, w, h)
        new = min(max(self.zoom * factor, MIN_ZOOM), MAX_ZOOM)
        if about is not None:
            px, py = about
            ratio = self.zoom / new
            cx, cy = px - (px - cx) * ratio, py - (py - cy) * ratio
        fx, fy = self._fit_centre(fit, w, h)
        self.zoom, self.pan_x, self.pan_y = new, cx - fx, cy - fy
        if abs(self.zoom - 1.0) < 1e-9 and abs(self.pan_x) < 1e-9 and abs(self.pan_y) < 1e-9:
            self.fit()

    @staticmethod
    def _fit_centre(fit: Frame, w: int, h: int) -> tuple[float, float]:
        return fit.x0 + w / (2 * fit.s), fit.y0 + (fit.top - h / 2) / fit.s

    def pan_cells(self, cols: float, rows: float, frame: Frame) -> None:
        """Move the view by cells (right and down positive): the map moves the other way."""
        self.pan_x += cols / frame.s
        self.pan_y -= 2 * rows / frame.s
