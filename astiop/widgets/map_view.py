"""The robot's map drawn with half blocks: two map pixels per terminal cell, one colour each.

The geometry comes from the robot layer: the known warehouse layout, the robot's /map grid,
or nothing, when the view follows the robot and shows what its scan sees. Names are written
over the map (the warehouse's stations and zones, the stored locations), and the last lines
say what each colour is.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from rich.segment import Segment
from rich.style import Style
from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget

from astiop.transports.state import OccupancyGrid, RobotState
from astiop.warehouse import WarehouseMap
from astiop.widgets.map_pixels import body_points, line_runs
from astiop.zones import MapZone, points_in_polygon

FOLLOW_HALF_M = 12.0  # with no map: metres shown either side of the robot


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
    "#7f1d1d",
    "#713f12",
]
FREE, WALL, SHELF, STATION, ZONE, OBSTACLE, PLAN, LIDAR, ROBOT, HEADING, LABEL = range(11)
KEEPOUT, SLOW = 11, 12  # the map's keepout and speed zones (astiop zones)
AREAS = (ZONE, KEEPOUT, SLOW)  # drawn under names, which keep their colour
_N = len(PALETTE)
_STYLES = {
    (t, b): Style(color=PALETTE[t], bgcolor=PALETTE[b]) for t in range(_N) for b in range(_N)
}
NAME_COLOUR = "#e5e7eb"
_NAME_STYLES = {b: Style(color=NAME_COLOUR, bgcolor=PALETTE[b]) for b in (FREE, *AREAS)}
_LEGEND_TEXT = Style(color="#9ca3af", bgcolor=PALETTE[FREE])
_BLANK = Style(bgcolor=PALETTE[FREE])
_SWATCHES = [Style(color=c, bgcolor=PALETTE[FREE]) for c in PALETTE]


class Place(NamedTuple):
    """A named location, drawn as a marker with its name."""

    name: str
    x: float
    y: float


class _Name(NamedTuple):
    """A name to write next to a box (metres): a station, a zone (written inside), a place."""

    text: str
    box: tuple[float, float, float, float]
    inside: bool = False


def legend_items(
    geometry, markers: bool, what: str = "locations", zones: tuple[MapZone, ...] = ()
) -> list[tuple[int, str]]:
    """What the view draws, as (palette index, what it is): only what this geometry can show."""
    items = [(ROBOT, "robot"), (HEADING, "heading"), (PLAN, "path"), (LIDAR, "LiDAR hits")]
    items.append((OBSTACLE, "obstacles seen"))
    if isinstance(geometry, WarehouseMap):
        items += [(WALL, "walls"), (SHELF, "racks"), (STATION, "stations"), (ZONE, "zones")]
    elif isinstance(geometry, OccupancyGrid):
        items.append((WALL, "occupied (/map)"))
    if any(z.kind == "keepout" for z in zones):
        items.append((KEEPOUT, "keepout"))
    if any(z.kind == "speed" for z in zones):
        items.append((SLOW, "speed limit"))
    if markers:
        items.append((LABEL, what))
    return items


class WarehouseMapView(Widget):
    DEFAULT_CSS = "WarehouseMapView { height: 1fr; width: 1fr; min-height: 10; }"
    markers_are = "locations"  # what the named markers are, in the legend (the Fleet's: robots)

    def __init__(self, geometry: WarehouseMap | OccupancyGrid | None, **kwargs):
        super().__init__(**kwargs)
        self.geometry = geometry
        self.robot_state: RobotState | None = None
        self.places: list[Place] = []  # named locations, drawn as markers with their names
        self.locations: list[tuple[float, float]] = []  # every marker, named or not
        self.zones: tuple[MapZone, ...] = ()  # the map's keepout and speed zones
        self._base: np.ndarray | None = None
        self._pixels: np.ndarray | None = None
        self._raster_size = (0, 0)
        self._names: dict[int, dict[int, str]] = {}  # cell row -> {column: character}
        self._legend: list[list[Segment]] = []
        self._legend_width = -1

    def set_locations(self, locations: list[Place] | list[tuple[float, float]]) -> None:
        """Markers: `Place`s are written with their name, bare (x, y) points are not."""
        self.places = [p for p in locations if isinstance(p, Place)]
        self.locations = [(p.x, p.y) if isinstance(p, Place) else tuple(p) for p in locations]
        self._base = self._pixels = None
        self._legend_width = -1
        self.refresh()

    def set_zones(self, zones: list[MapZone]) -> None:
        if tuple(zones) != self.zones:
            self.zones = tuple(zones)
            self._base = self._pixels = None
            self._legend_width = -1
            self.refresh()

    def set_geometry(self, geometry) -> None:
        if geometry is not self.geometry:
            self.geometry = geometry
            self._base = self._pixels = None
            self._legend_width = -1
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
        w, h = self.size.width, self._map_rows()
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
            # the changed lines alone: scan noise flips a few pixels far apart, and one region
            # spanning them redrew most of the map each sample
            self.refresh(*(Region(0, y0, w, n) for y0, n in line_runs(rows // 2)))

    # -- the legend -----------------------------------------------------------------------
    def _legend_lines(self, w: int) -> list[list[Segment]]:
        if self._legend_width != w:
            self._legend_width = w
            self._legend = []
            if self.geometry is None:
                note = "no map: the view follows the robot"
                self._legend.append([Segment(note[:w], _LEGEND_TEXT)])
            line: list[Segment] = []
            used = 0
            markers = bool(self.locations)
            for value, what in legend_items(self.geometry, markers, self.markers_are, self.zones):
                cells = len(what) + 4  # swatch, space, name, two spaces
                if line and used + cells - 2 > w:
                    self._legend.append(line)
                    line, used = [], 0
                # the space goes with the swatch: a text run starting with spaces loses them in
                # some SVG viewers (the snapshots)
                line += [Segment("█ ", _SWATCHES[value]), Segment(f"{what}  ", _LEGEND_TEXT)]
                used += cells
            if line:
                self._legend.append(line)
        return self._legend

    def _map_rows(self) -> int:
        """Rows left for the map under the legend; a small view gives up the legend first."""
        h = self.size.height
        legend = len(self._legend_lines(self.size.width))
        return h - legend if h - legend >= 6 else h

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
        if self.zones:
            self._fill_zones(px, s, x0, y0)
        if isinstance(geo, WarehouseMap):
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
        if self.locations:
            xs, ys = zip(*self.locations)
            self._plot(px, xs, ys, LABEL, s, x0, y0)
        self._names = self._place_names(px, s, x0, y0)
        return px

    def _fill_zones(self, px: np.ndarray, s: float, x0: float, y0: float) -> None:
        """Each pixel whose centre is inside a zone, in its kind's colour (keepout over speed)."""
        top = self._top(px, s)
        cols = np.arange(px.shape[1])
        rows = np.arange(px.shape[0])
        gx, gy = np.meshgrid(x0 + (cols + 0.5) / s, y0 + (top - rows - 0.5) / s)
        for zone in sorted(self.zones, key=lambda z: z.kind == "keepout"):
            px[points_in_polygon(gx, gy, zone.corners)] = (
                KEEPOUT if zone.kind == "keepout" else SLOW
            )

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
        bx, by = body_points(x, y, th)
        self._plot(px, bx, by, ROBOT, s, x0, y0)
        self._plot(px, [x + 0.8 * math.cos(th)], [y + 0.8 * math.sin(th)], HEADING, s, x0, y0)
        return px

    # -- names ----------------------------------------------------------------------------
    def _names_to_write(self) -> list[_Name]:
        names: list[_Name] = []
        geo = self.geometry
        if isinstance(geo, WarehouseMap):
            names += [_Name(st.name, st.rect) for st in geo.stations]
            names += [_Name(z.name, z.rect, inside=True) for z in geo.zones]
        for z in self.zones:
            xs, ys = zip(*z.corners)
            names.append(_Name(z.name, (min(xs), min(ys), max(xs), max(ys)), inside=True))
        written = {n.text for n in names}
        names += [_Name(p.name, (p.x, p.y, p.x, p.y)) for p in self.places if p.name not in written]
        return names

    def _place_names(self, px: np.ndarray, s: float, x0: float, y0: float) -> dict:
        """Each name where it covers the fewest drawn cells and no other name; one that fits
        nowhere is left out."""
        rows, w = px.shape[0] // 2, px.shape[1]
        top = self._top(px, s)
        floor = (FREE, *AREAS)
        drawn = ~np.isin(px[0::2], floor) | ~np.isin(px[1::2], floor)
        markers = (px[0::2] == LABEL) | (px[1::2] == LABEL)
        taken = np.zeros((rows, w), dtype=bool)
        out: dict[int, dict[int, str]] = {}

        def cell(x: float, y: float) -> tuple[int, int]:
            return (top - 1 - math.floor((y - y0) * s)) // 2, math.floor((x - x0) * s)

        for name in self._names_to_write():
            n = len(name.text)
            if n > w:
                continue
            r0, c0 = cell(name.box[0], name.box[3])
            r1, c1 = cell(name.box[2], name.box[1])
            if r1 < 0 or r0 >= rows or c1 < 0 or c0 >= w:
                continue  # out of view: not written at an edge
            mid_r, mid_c = (r0 + r1) // 2, (c0 + c1) // 2
            candidates = [(mid_r, mid_c - n // 2)] if name.inside else []
            candidates += [
                (mid_r, c1 + 2),
                (mid_r, c0 - 1 - n),
                (r1 + 1, mid_c - n // 2),
                (r0 - 1, mid_c - n // 2),
                (mid_r + 1, c1 + 2),
                (mid_r - 1, c1 + 2),
                (mid_r + 1, c0 - 1 - n),
                (mid_r - 1, c0 - 1 - n),
            ]
            best = None
            for order, (r, c) in enumerate(candidates):
                c = min(max(c, 0), w - n)
                if not 0 <= r < rows or taken[r, max(c - 2, 0) : c + n + 2].any():
                    continue
                cost = (
                    int(drawn[r, c : c + n].sum()) + 4 * int(markers[r, c : c + n].sum()),
                    order,
                )
                if best is None or cost < best[0]:
                    best = (cost, r, c)
            if best is None:
                continue
            _, r, c = best
            taken[r, c : c + n] = True
            out.setdefault(r, {}).update({c + i: ch for i, ch in enumerate(name.text)})
        return out

    # -- Textual's line API ---------------------------------------------------------------
    def render_line(self, y: int) -> Strip:
        w, h = self.size.width, self._map_rows()
        if w <= 0 or h <= 0:
            return Strip.blank(w)
        if y >= h:
            legend = self._legend_lines(w)
            i = y - h
            line = legend[i] if i < len(legend) else []
            return Strip(line).adjust_cell_length(w, _BLANK)
        if self._pixels is None or self._pixels.shape != (2 * h, w):
            self._pixels = self._raster(w, 2 * h)
        top, bottom = self._pixels[2 * y], self._pixels[2 * y + 1]
        names = self._names.get(y, {})
        segments = []
        run: list[str] = []
        run_style = None
        for x in range(w):
            t, b = int(top[x]), int(bottom[x])
            ch = names.get(x)
            if ch is not None and not ({t, b} & {ROBOT, HEADING}):
                # a name over a zone keeps the zone's colour; elsewhere it is written on the floor
                style = _NAME_STYLES[t if t == b and t in AREAS else FREE]
            else:
                ch, style = "▀", _STYLES[(t, b)]
            if style is not run_style and run:
                segments.append(Segment("".join(run), run_style))
                run = []
            run.append(ch)
            run_style = style
        if run:
            segments.append(Segment("".join(run), run_style))
        return Strip(segments, w)
