"""The robot's map drawn with half blocks: two map pixels per terminal cell, one colour each.

The geometry comes from the robot layer: the known warehouse layout, the robot's /map grid,
or nothing, when the view follows the robot and shows what its scan sees.
"""

from __future__ import annotations

import math

import numpy as np
from rich.segment import Segment
from rich.style import Style
from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget

from astiop.robot.state import OccupancyGrid, RobotState
from astiop.warehouse import WarehouseMap

FOLLOW_HALF_M = 12.0  # with no map: metres shown either side of the robot


def _body_points(x: float, y: float, th: float, length: float = 1.0, width: float = 0.735):
    c, s = math.cos(th), math.sin(th)
    u = np.linspace(-length / 2, length / 2, 6)
    v = np.linspace(-width / 2, width / 2, 5)
    gu, gv = (a.ravel() for a in np.meshgrid(u, v))
    return x + gu * c - gv * s, y + gu * s + gv * c


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

    def __init__(self, geometry: WarehouseMap | OccupancyGrid | None, **kwargs):
        super().__init__(**kwargs)
        self.geometry = geometry
        self.robot_state: RobotState | None = None
        self.locations: list[tuple[float, float]] = []  # named locations, drawn as markers
        self._base: np.ndarray | None = None
        self._pixels: np.ndarray | None = None
        self._raster_size = (0, 0)

    def set_locations(self, points: list[tuple[float, float]]) -> None:
        self.locations = list(points)
        self._pixels = None
        self.refresh()

    def set_geometry(self, geometry) -> None:
        if geometry is not self.geometry:
            self.geometry = geometry
            self._base = self._pixels = None
            self.refresh()

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        if self.geometry is not None:
            return self.geometry.bounds
        st = self.robot_state
        cx, cy = (st.pose.x, st.pose.y) if st and st.pose else (0.0, 0.0)
        h = FOLLOW_HALF_M
        return (cx - h, cy - h / 2, cx + h, cy + h / 2)

    def show(self, state: RobotState) -> None:
        self.robot_state = state
        if self.geometry is None:
            self._base = None  # the view moves with the robot
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
        x0, y0, x1, y1 = self.bounds
        # keep metres square: a cell is twice as tall as wide, two pixels per cell vertically
        s = min(w / (x1 - x0), h / (y1 - y0))
        return s, x0, y0

    def _top(self, px: np.ndarray, s: float) -> int:
        """Pixel row of the map's top edge: the drawing is centred vertically."""
        map_h = int(math.ceil((self.bounds[3] - self.bounds[1]) * s))
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
        geo = self.geometry
        if isinstance(geo, WarehouseMap):
            for zone in geo.zones:
                self._fill_rect(px, zone.rect, ZONE, s, x0, y0)
            for kind, rect in geo.static_rects:
                value = (
                    WALL if kind in ("wall", "pillar") else SHELF if kind == "shelf" else STATION
                )
                self._fill_rect(px, rect, value, s, x0, y0)
        elif isinstance(geo, OccupancyGrid):
            rows, cols = np.nonzero(geo.cells >= 50)
            xs = geo.origin_x + (cols + 0.5) * geo.resolution
            ys = geo.origin_y + (rows + 0.5) * geo.resolution
            self._plot(px, xs, ys, WALL, s, x0, y0)
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
        if st is None or st.pose is None or not math.isfinite(st.pose.x):
            return px  # no pose reported: the map alone
        x, y, th = st.pose.x, st.pose.y, st.pose.theta
        for ob in st.obstacles or ():  # what the robot detected, not what the sim knows
            half = max(ob.size, 0.3) / 2
            rect = (ob.x - half, ob.y - half, ob.x + half, ob.y + half)
            self._fill_rect(px, rect, OBSTACLE, s, x0, y0)
        for (ax, ay), (bx, by) in zip(st.plan, st.plan[1:]):
            n = max(int(math.dist((ax, ay), (bx, by)) * s * 2), 2)
            self._plot(px, np.linspace(ax, bx, n), np.linspace(ay, by, n), PLAN, s, x0, y0)
        scan = st.scan
        if scan is not None and len(scan.ranges):
            finite = np.isfinite(scan.ranges)
            ang = th + scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
            r = scan.ranges[finite]
            self._plot(
                px, x + r * np.cos(ang[finite]), y + r * np.sin(ang[finite]), LIDAR, s, x0, y0
            )
        bx, by = _body_points(x, y, th)
        self._plot(px, bx, by, ROBOT, s, x0, y0)
        self._plot(px, [x + 0.8 * math.cos(th)], [y + 0.8 * math.sin(th)], HEADING, s, x0, y0)
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
