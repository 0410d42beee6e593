"""The robot's map drawn with half blocks: two map pixels per terminal cell, one colour each.

The geometry comes from the robot layer: the known warehouse layout, the robot's /map grid,
or nothing, when the view follows the robot and shows what its scan sees. Names are written
over the map (the warehouse's stations and zones, the stored locations, a fleet's other robots),
and the last lines say what each colour is. Where it looks is its `Viewport`'s (zoom, pan); the
keyboard's cursor and a zone being drawn are drawn over it (`map_view` moves them).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from rich.segment import Segment
from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget

from astiop.transports.state import OccupancyGrid, RobotState
from astiop.warehouse import WarehouseMap
from astiop.widgets.map_legend import (
    AREAS,
    BLANK,
    CURSOR,
    DRAFT,
    FREE,
    HEADING,
    KEEPOUT,
    LABEL,
    LIDAR,
    NAME_STYLES,
    OBSTACLE,
    OTHER,
    OTHER_PLAN,
    PLAN,
    ROBOT,
    SHELF,
    SLOW,
    STATION,
    STYLES,
    WALL,
    ZONE,
    legend_items,
    legend_lines,
)
from astiop.widgets.map_names import Name, place_names
from astiop.widgets.map_pixels import (
    body_points,
    fill_polygons,
    fill_rect,
    line_runs,
    plot,
    polyline,
)
from astiop.widgets.map_viewport import Frame, Viewport
from astiop.zones import MapZone, points_in_polygon

FOLLOW_HALF_M = 12.0  # with no map: metres shown either side of the robot


class Place(NamedTuple):
    """A named location, drawn as a marker with its name."""

    name: str
    x: float
    y: float


class FleetRobot(NamedTuple):
    """Another robot of the fleet, drawn with its heading and its plan, named."""

    name: str
    x: float
    y: float
    theta: float
    plan: tuple[tuple[float, float], ...] = ()


class MapCanvas(Widget):
    DEFAULT_CSS = "MapCanvas { height: 1fr; width: 1fr; min-height: 10; }"
    markers_are = "locations"  # what the named markers are, in the legend (the Fleet's: robots)

    def __init__(self, geometry: WarehouseMap | OccupancyGrid | None, **kwargs):
        super().__init__(**kwargs)
        self.geometry = geometry
        self.robot_state: RobotState | None = None
        self.places: list[Place] = []  # named locations, drawn as markers with their names
        self.locations: list[tuple[float, float]] = []  # every marker, named or not
        self.zones: tuple[MapZone, ...] = ()  # the map's keepout and speed zones
        self.others: tuple[FleetRobot, ...] = ()  # a fleet's other robots
        self.viewport = Viewport()
        self.cursor: tuple[int, int] | None = None  # the keyboard's cell (column, row)
        self.draft: list[tuple[float, float]] | None = None  # a zone's corners while drawn
        self._base: np.ndarray | None = None
        self._pixels: np.ndarray | None = None
        self._raster_size = (0, 0)
        self._names: dict[int, dict[int, str]] = {}  # cell row -> {column: character}
        self._legend: list[list[Segment]] = []
        self._legend_width = -1

    def _redraw(self) -> None:
        self._base = self._pixels = None
        self._legend_width = -1
        self.refresh()

    def set_locations(self, locations: list[Place] | list[tuple[float, float]]) -> None:
        """Markers: `Place`s are written with their name, bare (x, y) points are not."""
        self.places = [p for p in locations if isinstance(p, Place)]
        self.locations = [(p.x, p.y) if isinstance(p, Place) else (p[0], p[1]) for p in locations]
        self._redraw()

    def set_zones(self, zones: list[MapZone]) -> None:
        if tuple(zones) != self.zones:
            self.zones = tuple(zones)
            self._redraw()

    def set_fleet(self, others: list[FleetRobot]) -> None:
        if tuple(others) != self.others:
            self.others = tuple(others)
            self._redraw()

    def set_geometry(self, geometry) -> None:
        if geometry is not self.geometry:
            self.geometry = geometry
            self._redraw()

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        if self.geometry is not None:
            return self.geometry.bounds
        st = self.robot_state
        cx, cy = (st.pose.x, st.pose.y) if st and st.pose else (0.0, 0.0)
        h = FOLLOW_HALF_M
        return (cx - h, cy - h / 2, cx + h, cy + h / 2)

    @property
    def frame(self) -> Frame:
        """Metres to this view's pixels, as it is drawn now."""
        return self.viewport.frame(self.size.width, 2 * self._map_rows(), self.bounds)

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

    def _legend_lines(self, w: int) -> list[list[Segment]]:
        if self._legend_width != w:
            self._legend_width = w
            items = legend_items(self.geometry, bool(self.locations), self.markers_are,
                                 self.zones, bool(self.others), self.draft is not None)  # fmt: skip
            self._legend = legend_lines(w, items, self.geometry is None)
        return self._legend

    def _map_rows(self) -> int:
        """Rows left for the map under the legend; a small view gives up the legend first."""
        h = self.size.height
        legend = len(self._legend_lines(self.size.width))
        return h - legend if h - legend >= 6 else h

    # -- rasterising ----------------------------------------------------------------------
    def _base_layer(self, w: int, h: int) -> np.ndarray:
        px = np.full((h, w), FREE, dtype=np.int8)
        frame = self.viewport.frame(w, h, self.bounds)
        geo = self.geometry
        if isinstance(geo, WarehouseMap):
            for zone in geo.zones:
                fill_rect(px, zone.rect, ZONE, frame)
        # keepout over speed
        areas = sorted(self.zones, key=lambda z: z.kind == "keepout")
        polygons = [(z.corners, KEEPOUT if z.kind == "keepout" else SLOW) for z in areas]
        if polygons:
            fill_polygons(px, polygons, frame, points_in_polygon)
        if isinstance(geo, WarehouseMap):
            for kind, rect in geo.static_rects:
                value = (
                    WALL if kind in ("wall", "pillar") else SHELF if kind == "shelf" else STATION
                )
                fill_rect(px, rect, value, frame)
        elif isinstance(geo, OccupancyGrid):
            rows, cols = np.nonzero(geo.cells >= 50)
            xs = geo.origin_x + (cols + 0.5) * geo.resolution
            ys = geo.origin_y + (rows + 0.5) * geo.resolution
            plot(px, xs, ys, WALL, frame)
        if self.locations:
            plot(px, [p[0] for p in self.locations], [p[1] for p in self.locations], LABEL, frame)
        for other in self.others:  # at the fleet's pace (2 Hz), not each sample
            polyline(px, other.plan, OTHER_PLAN, frame)
            bx, by = body_points(other.x, other.y, other.theta)
            plot(px, bx, by, OTHER, frame)
            ahead = (other.x + 0.8 * math.cos(other.theta), other.y + 0.8 * math.sin(other.theta))
            plot(px, [ahead[0]], [ahead[1]], HEADING, frame)
        self._names = place_names(px, frame, self._names_to_write(), (FREE, *AREAS), LABEL)
        return px

    def _raster(self, w: int, h: int) -> np.ndarray:
        if self._base is None or self._raster_size != (w, h):
            self._base, self._raster_size = self._base_layer(w, h), (w, h)
        px = self._base.copy()
        frame = self.viewport.frame(w, h, self.bounds)
        if self.draft:
            polyline(px, self.draft, DRAFT, frame)
            plot(px, [p[0] for p in self.draft], [p[1] for p in self.draft], DRAFT, frame)
        st = self.robot_state
        if st is None or st.pose is None or not math.isfinite(st.pose.x):
            return px  # no pose reported: the map alone
        x, y, th = st.pose.x, st.pose.y, st.pose.theta
        for ob in st.obstacles or ():  # what the robot detected, not what the sim knows
            half = max(ob.size, 0.3) / 2
            fill_rect(px, (ob.x - half, ob.y - half, ob.x + half, ob.y + half), OBSTACLE, frame)
        polyline(px, st.plan, PLAN, frame)
        scan = st.scan
        if scan is not None and len(scan.ranges):
            finite = np.isfinite(scan.ranges)
            ang = th + scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))
            r = scan.ranges[finite]
            plot(px, x + r * np.cos(ang[finite]), y + r * np.sin(ang[finite]), LIDAR, frame)
        bx, by = body_points(x, y, th)
        plot(px, bx, by, ROBOT, frame)
        plot(px, [x + 0.8 * math.cos(th)], [y + 0.8 * math.sin(th)], HEADING, frame)
        return px

    def _names_to_write(self) -> list[Name]:
        names: list[Name] = [Name(r.name, (r.x - 0.5, r.y - 0.5, r.x + 0.5, r.y + 0.5))
                             for r in self.others]  # fmt: skip
        geo = self.geometry
        if isinstance(geo, WarehouseMap):
            names += [Name(st.name, st.rect) for st in geo.stations]
            names += [Name(z.name, z.rect, inside=True) for z in geo.zones]
        for z in self.zones:
            xs, ys = zip(*z.corners)
            names.append(Name(z.name, (min(xs), min(ys), max(xs), max(ys)), inside=True))
        written = {n.text for n in names}
        names += [Name(p.name, (p.x, p.y, p.x, p.y)) for p in self.places if p.name not in written]
        return names

    # -- Textual's line API ---------------------------------------------------------------
    def render_line(self, y: int) -> Strip:
        w, h = self.size.width, self._map_rows()
        if w <= 0 or h <= 0:
            return Strip.blank(w)
        if y >= h:
            legend = self._legend_lines(w)
            i = y - h
            line = legend[i] if i < len(legend) else []
            return Strip(line).adjust_cell_length(w, BLANK)
        if self._pixels is None or self._pixels.shape != (2 * h, w):
            self._pixels = self._raster(w, 2 * h)
        top, bottom = self._pixels[2 * y], self._pixels[2 * y + 1]
        names = self._names.get(y, {})
        cursor = self.cursor if self.has_focus or self.draft is not None else None
        cursor_x = cursor[0] if cursor is not None and cursor[1] == y else -1
        segments = []
        run: list[str] = []
        run_style = None
        for x in range(w):
            t, b = int(top[x]), int(bottom[x])
            ch = names.get(x)
            if x == cursor_x:
                ch, style = "+", CURSOR
            elif ch is not None and not ({t, b} & {ROBOT, HEADING}):
                # a name over a zone keeps the zone's colour; elsewhere it is written on the floor
                style = NAME_STYLES[t if t == b and t in AREAS else FREE]
            else:
                ch, style = "▀", STYLES[(t, b)]
            if style is not run_style and run:
                segments.append(Segment("".join(run), run_style))
                run = []
            run.append(ch)
            run_style = style
        if run:
            segments.append(Segment("".join(run), run_style))
        return Strip(segments, w)
