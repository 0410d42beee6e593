"""The warehouse drawn with half blocks: two map pixels per terminal cell, one colour each."""

from __future__ import annotations

import math

import numpy as np
from rich.segment import Segment
from rich.style import Style
from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget

from astiop.sim.geometry import oriented_box
from astiop.sim.state import SimState
from astiop.sim.warehouse_map import WarehouseMap

# palette index -> colour
PALETTE = [
    "#1b1f24",
    "#6b7280",
    "#a16207",
    "#2563eb",
    "#374151",
    "#f97316",
    "#22d3ee",
    "#ef4444",
    "#22c55e",
    "#facc15",
    "#c084fc",
]
FREE, WALL, SHELF, STATION, ZONE, OBSTACLE, PLAN, LIDAR, ROBOT, HEADING, LABEL = range(11)
_STYLES = {
    (t, b): Style(color=PALETTE[t], bgcolor=PALETTE[b]) for t in range(11) for b in range(11)
}


class WarehouseMapView(Widget):
    DEFAULT_CSS = "WarehouseMapView { height: 1fr; width: 1fr; min-height: 10; }"

    def __init__(self, warehouse: WarehouseMap, **kwargs):
        super().__init__(**kwargs)
        self.warehouse = warehouse
        self.robot_state: SimState | None = None
        self.locations: list[tuple[float, float]] = []  # named locations, drawn as markers
        self._base: np.ndarray | None = None
        self._pixels: np.ndarray | None = None
        self._raster_size = (0, 0)

    def set_locations(self, points: list[tuple[float, float]]) -> None:
        self.locations = list(points)
        self._pixels = None
        self.refresh()

    def show(self, state: SimState) -> None:
        self.robot_state = state
        w, h = self.size.width, self.size.height
        if w <= 0 or h <= 0:
            return
        pixels = self._raster(w, 2 * h)
        # lidar noise rarely moves a half-metre pixel: redraw only what changed
        if self._pixels is None or self._pixels.shape != pixels.shape:
            self._pixels = pixels
            self.refresh()
            return
        rows = np.nonzero((pixels != self._pixels).any(axis=1))[0]
        self._pixels = pixels
        if len(rows):
            y0, y1 = int(rows.min()) // 2, int(rows.max()) // 2
            self.refresh(Region(0, y0, w, y1 - y0 + 1))

    # -- rasterising ----------------------------------------------------------------------
    def _scale(self, w: int, h: int) -> tuple[float, float, float]:
        x0, y0, x1, y1 = self.warehouse.bounds
        # keep metres square: a cell is twice as tall as wide, two pixels per cell vertically
        s = min(w / (x1 - x0), h / (y1 - y0))
        return s, x0, y0

    def _top(self, px: np.ndarray, s: float) -> int:
        """Pixel row of the map's top edge: the drawing is centred vertically."""
        map_h = int(math.ceil((self.warehouse.bounds[3] - self.warehouse.bounds[1]) * s))
        return px.shape[0] - max((px.shape[0] - map_h) // 2, 0)

    def _fill_rect(self, px: np.ndarray, rect, value: int, s, x0, y0) -> None:
        h = self._top(px, s)
        c0 = int(math.floor((rect[0] - x0) * s))
        c1 = int(math.ceil((rect[2] - x0) * s))
        r0 = h - int(math.ceil((rect[3] - y0) * s))
        r1 = h - int(math.floor((rect[1] - y0) * s))
        px[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = value

    def _base_layer(self, w: int, h: int) -> np.ndarray:
        px = np.full((h, w), FREE, dtype=np.int8)
        s, x0, y0 = self._scale(w, h)
        for zone in self.warehouse.zones:
            self._fill_rect(px, zone.rect, ZONE, s, x0, y0)
        for kind, rect in self.warehouse.static_rects:
            value = WALL if kind in ("wall", "pillar") else SHELF if kind == "shelf" else STATION
            self._fill_rect(px, rect, value, s, x0, y0)
        return px

    def _plot(self, px, xs, ys, value, s, x0, y0) -> None:
        full_h, w = px.shape
        h = self._top(px, s)
        cols = np.floor((np.asarray(xs) - x0) * s).astype(int)
        rows = h - 1 - np.floor((np.asarray(ys) - y0) * s).astype(int)
        ok = (cols >= 0) & (cols < w) & (rows >= 0) & (rows < full_h)
        px[rows[ok], cols[ok]] = value

    def _raster(self, w: int, h: int) -> np.ndarray:
        if self._base is None or self._raster_size != (w, h):
            self._base, self._raster_size = self._base_layer(w, h), (w, h)
        px = self._base.copy()
        s, x0, y0 = self._scale(w, h)
        if self.locations:
            xs, ys = zip(*self.locations)
            self._plot(px, xs, ys, LABEL, s, x0, y0)
        st = self.robot_state
        if st is None:
            return px
        for ob in st.obstacles:
            pts = ob.outline()
            self._fill_rect(px, (*pts.min(axis=0), *pts.max(axis=0)), OBSTACLE, s, x0, y0)
        for (ax, ay), (bx, by) in zip(st.plan, st.plan[1:]):
            n = max(int(math.dist((ax, ay), (bx, by)) * s * 2), 2)
            self._plot(px, np.linspace(ax, bx, n), np.linspace(ay, by, n), PLAN, s, x0, y0)
        finite = np.isfinite(st.scan_ranges)
        if finite.any():
            ang = st.theta + (
                -math.pi + 2 * math.pi / len(st.scan_ranges) * np.arange(len(st.scan_ranges))
            )
            r = st.scan_ranges[finite]
            self._plot(
                px, st.x + r * np.cos(ang[finite]), st.y + r * np.sin(ang[finite]), LIDAR, s, x0, y0
            )
        body = oriented_box(st.x, st.y, st.theta, 1.0, 0.735)
        gx, gy = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 5))
        a, b, d = body[0], body[1], body[3]
        pts = a + np.outer(gx.ravel(), b - a) + np.outer(gy.ravel(), d - a)
        self._plot(px, pts[:, 0], pts[:, 1], ROBOT, s, x0, y0)
        hx, hy = st.x + 0.8 * math.cos(st.theta), st.y + 0.8 * math.sin(st.theta)
        self._plot(px, [hx], [hy], HEADING, s, x0, y0)
        return px

    # -- Textual's line API ---------------------------------------------------------------
    def render_line(self, y: int) -> Strip:
        w, h = self.size.width, self.size.height
        if w <= 0 or h <= 0:
            return Strip.blank(w)
        if self._pixels is None or self._pixels.shape != (2 * h, w):
            self._pixels = self._raster(w, 2 * h)
        top, bottom = self._pixels[2 * y], self._pixels[2 * y + 1]
        segments = []
        run_start = 0
        for x in range(1, w + 1):
            if x == w or top[x] != top[run_start] or bottom[x] != bottom[run_start]:
                style = _STYLES[(int(top[run_start]), int(bottom[run_start]))]
                segments.append(Segment("▀" * (x - run_start), style))
                run_start = x
        return Strip(segments, w)
