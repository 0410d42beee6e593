"""The map view's colours, and its legend: what each colour is, only what the view can show."""

from __future__ import annotations

from rich.segment import Segment
from rich.style import Style

from astiop.transports.state import OccupancyGrid
from astiop.warehouse import WarehouseMap
from astiop.zones import MapZone

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
    "#f472b6",
    "#be185d",
    "#f8fafc",
]
FREE, WALL, SHELF, STATION, ZONE, OBSTACLE, PLAN, LIDAR, ROBOT, HEADING, LABEL = range(11)
KEEPOUT, SLOW = 11, 12  # the map's keepout and speed zones (astiop zones)
OTHER, OTHER_PLAN, DRAFT = 13, 14, 15  # a fleet's other robots, their paths; a zone being drawn
AREAS = (ZONE, KEEPOUT, SLOW)  # drawn under names, which keep their colour
_N = len(PALETTE)
STYLES = {(t, b): Style(color=PALETTE[t], bgcolor=PALETTE[b]) for t in range(_N) for b in range(_N)}
NAME_COLOUR = "#e5e7eb"
NAME_STYLES = {b: Style(color=NAME_COLOUR, bgcolor=PALETTE[b]) for b in (FREE, *AREAS)}
LEGEND_TEXT = Style(color="#9ca3af", bgcolor=PALETTE[FREE])
BLANK = Style(bgcolor=PALETTE[FREE])
SWATCHES = [Style(color=c, bgcolor=PALETTE[FREE]) for c in PALETTE]
CURSOR = Style(color="#000000", bgcolor="#f8fafc", bold=True)


def legend_items(
    geometry,
    markers: bool,
    what: str = "locations",
    zones: tuple[MapZone, ...] = (),
    others: bool = False,
    drawing: bool = False,
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
    if others:
        items += [(OTHER, "other robots"), (OTHER_PLAN, "their paths")]
    if drawing:
        items.append((DRAFT, "new zone"))
    return items


def legend_lines(w: int, items: list[tuple[int, str]], follows: bool) -> list[list[Segment]]:
    """The legend wrapped to `w` cells; `follows`: there is no map, the view follows the robot."""
    lines: list[list[Segment]] = []
    if follows:
        note = "no map: the view follows the robot"
        lines.append([Segment(note[:w], LEGEND_TEXT)])
    line: list[Segment] = []
    used = 0
    for value, what in items:
        cells = len(what) + 4  # swatch, space, name, two spaces
        if line and used + cells - 2 > w:
            lines.append(line)
            line, used = [], 0
        # the space goes with the swatch: a text run starting with spaces loses them in some SVG
        # viewers (the snapshots)
        line += [Segment("█ ", SWATCHES[value]), Segment(f"{what}  ", LEGEND_TEXT)]
        used += cells
    if line:
        lines.append(line)
    return lines
