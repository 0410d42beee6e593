"""Zones of a map as plain geometry: `keepout` (no goal inside, no plan through, no teleop into)
and `speed` (a lower speed limit inside). Shared by the store (validation), safety (goals,
teleop), the simulator (planner, controller) and the Nav2 export; imports nothing of astiop."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

KINDS = ("keepout", "speed")
MAX_CORNERS = 64
MAX_SPEED = 10.0  # m/s: a speed zone's limit above this is a typo
NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")

Point = tuple[float, float]


class ZoneError(ValueError):
    """A zone request is invalid; nothing was changed."""


@dataclass(frozen=True)
class MapZone:
    name: str
    kind: str  # keepout | speed
    corners: tuple[Point, ...]
    speed: float | None = None  # m/s, a speed zone's limit

    def contains(self, x: float, y: float) -> bool:
        return point_in_polygon(x, y, self.corners)

    @property
    def words(self) -> str:
        """How a refusal or a note names it."""
        if self.kind == "speed":
            return f"speed zone '{self.name}' ({self.speed:g} m/s)"
        return f"keepout zone '{self.name}'"

    def as_json(self) -> dict:
        return {
            "name": self.name,
            "kind": self.kind,
            "corners": [[round(x, 4), round(y, 4)] for x, y in self.corners],
            "speed": self.speed,
        }


def point_in_polygon(x: float, y: float, corners: Sequence[Point]) -> bool:
    """Even-odd rule; a point on an edge counts as inside (a zone's border is the zone's)."""
    inside = False
    n = len(corners)
    for i in range(n):
        (x0, y0), (x1, y1) = corners[i], corners[(i + 1) % n]
        if _on_segment(x, y, x0, y0, x1, y1):
            return True
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def _on_segment(px: float, py: float, x0: float, y0: float, x1: float, y1: float) -> bool:
    cross = (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)
    if abs(cross) > 1e-9 * max(1.0, math.hypot(x1 - x0, y1 - y0)):
        return False
    return min(x0, x1) - 1e-9 <= px <= max(x0, x1) + 1e-9 and (
        min(y0, y1) - 1e-9 <= py <= max(y0, y1) + 1e-9
    )


def _orient(a: Point, b: Point, c: Point) -> float:
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def segments_cross(a: Point, b: Point, c: Point, d: Point) -> bool:
    """Whether segment ab meets segment cd (touching counts)."""
    o1, o2, o3, o4 = _orient(a, b, c), _orient(a, b, d), _orient(c, d, a), _orient(c, d, b)
    if (o1 > 0) != (o2 > 0) and (o3 > 0) != (o4 > 0) and o1 and o2 and o3 and o4:
        return True
    return (
        (o1 == 0 and _on_segment(*c, *a, *b))
        or (o2 == 0 and _on_segment(*d, *a, *b))
        or (o3 == 0 and _on_segment(*a, *c, *d))
        or (o4 == 0 and _on_segment(*b, *c, *d))
    )


def polygon_area(corners: Sequence[Point]) -> float:
    n = len(corners)
    return 0.5 * abs(
        sum(
            corners[i][0] * corners[(i + 1) % n][1] - corners[(i + 1) % n][0] * corners[i][1]
            for i in range(n)
        )
    )


def self_crossing(corners: Sequence[Point]) -> tuple[int, int] | None:
    """The first two edges (by their first corner's index) that meet though not neighbours."""
    n = len(corners)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # the closing edge and the first share corner 0
            if segments_cross(corners[i], corners[(i + 1) % n], corners[j], corners[(j + 1) % n]):
                return i, j
    return None


def parse_corner(text: str) -> Point:
    """ "x,y" in metres; ZoneError saying which corner is bad."""
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        x, y = float(parts[0]), float(parts[1])
    except ValueError:
        raise ZoneError(f"bad corner '{text[:40]}': write each corner as x,y in metres") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ZoneError(f"bad corner '{text[:40]}': x and y must be finite numbers")
    return x, y


def check_zone(
    name: str,
    kind: str,
    corners: Sequence[Point],
    speed: float | None,
    bounds: tuple[float, float, float, float] | None,
) -> MapZone:
    """The zone, or a ZoneError naming the first thing wrong with it."""
    if not NAME_RE.match(name or ""):
        raise ZoneError(f"invalid zone name '{name[:80]}': use 1-64 letters, digits, '_' or '-'")
    if kind not in KINDS:
        raise ZoneError(f"a zone is keepout or speed, not '{kind[:40]}'")
    if len(corners) < 3:
        raise ZoneError(f"a zone needs at least 3 corners, {len(corners)} given")
    if len(corners) > MAX_CORNERS:
        raise ZoneError(f"a zone has at most {MAX_CORNERS} corners, {len(corners)} given")
    corners = tuple((float(x), float(y)) for x, y in corners)
    if not all(math.isfinite(v) for c in corners for v in c):
        raise ZoneError("corners must be finite numbers")
    if bounds is not None:
        x0, y0, x1, y1 = bounds
        for x, y in corners:
            if not (x0 <= x <= x1 and y0 <= y <= y1):
                raise ZoneError(
                    f"corner ({x:g}, {y:g}) is outside the map (x {x0:g}..{x1:g}, "
                    f"y {y0:g}..{y1:g} m)"
                )
    if len(set(corners)) != len(corners):
        raise ZoneError("a corner is given twice")
    crossing = self_crossing(corners)
    if crossing is not None:
        i, j = crossing
        raise ZoneError(
            f"the polygon crosses itself (edge {i + 1}-{i + 2} meets edge {j + 1}-"
            f"{(j + 1) % len(corners) + 1}): give the corners in order around the zone"
        )
    if polygon_area(corners) < 1e-6:
        raise ZoneError("the polygon has no area (its corners are on one line)")
    if kind == "speed":
        if speed is None or not math.isfinite(speed) or not 0 < speed <= MAX_SPEED:
            raise ZoneError(f"a speed zone's limit is a speed in m/s, > 0 and <= {MAX_SPEED:g}")
    else:
        speed = None
    return MapZone(name, kind, corners, speed)


def zone_at(zones: Iterable[MapZone], x: float, y: float, kind: str) -> MapZone | None:
    """The first zone of that kind containing (x, y); for speed zones the slowest one."""
    found = [z for z in zones if z.kind == kind and z.contains(x, y)]
    if not found:
        return None
    return min(found, key=lambda z: z.speed or 0.0) if kind == "speed" else found[0]


def segment_distance(p: Point, q: Point, a: Point, b: Point) -> float:
    """The shortest distance between segments pq and ab."""
    if segments_cross(p, q, a, b):
        return 0.0
    return min(
        _point_segment(p, a, b),
        _point_segment(q, a, b),
        _point_segment(a, p, q),
        _point_segment(b, p, q),
    )


def _point_segment(p: Point, a: Point, b: Point) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    n = dx * dx + dy * dy
    t = 0.0 if n == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / n))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def polygon_distance(x: float, y: float, corners: Sequence[Point]) -> float:
    """0 inside, else the distance to the nearest edge."""
    if point_in_polygon(x, y, corners):
        return 0.0
    n = len(corners)
    return min(_point_segment((x, y), corners[i], corners[(i + 1) % n]) for i in range(n))


# -- over arrays (the planner's many segments, the masks' many pixels) ---------------------------
def points_in_polygon(xs: np.ndarray, ys: np.ndarray, corners: Sequence[Point]) -> np.ndarray:
    """Even-odd point-in-polygon over arrays of points (edges not included)."""
    inside = np.zeros(np.shape(xs), dtype=bool)
    n = len(corners)
    for i in range(n):
        (x0, y0), (x1, y1) = corners[i], corners[(i + 1) % n]
        if y0 == y1:
            continue
        crosses = (y0 > ys) != (y1 > ys)
        at = x0 + (ys - y0) * (x1 - x0) / (y1 - y0)
        inside ^= crosses & (xs < at)
    return inside


def _point_segment_v(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    n = (d * d).sum(-1)
    t = np.clip(((p - a) * d).sum(-1) / np.where(n == 0, 1.0, n), 0.0, 1.0)
    return np.hypot(*np.moveaxis(p - a - t[..., None] * d, -1, 0))


def segments_polygon_distance(p: np.ndarray, q: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """The distance from each segment p[i]-q[i] to a polygon: 0 where it crosses an edge or an
    end is inside."""
    a = corners[None, :, :]
    b = np.roll(corners, -1, axis=0)[None, :, :]
    P, Q = p[:, None, :], q[:, None, :]

    def orient(u, v, w):
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (
            w[..., 0] - u[..., 0]
        )

    crossing = (
        (np.sign(orient(P, Q, a)) * np.sign(orient(P, Q, b)) < 0)
        & (np.sign(orient(a, b, P)) * np.sign(orient(a, b, Q)) < 0)
    ).any(axis=1)
    near = np.minimum.reduce(
        [
            _point_segment_v(P, a, b),
            _point_segment_v(Q, a, b),
            _point_segment_v(a, P, Q),
            _point_segment_v(b, P, Q),
        ]
    ).min(axis=1)
    inside = points_in_polygon(p[:, 0], p[:, 1], corners) | points_in_polygon(
        q[:, 0], q[:, 1], corners
    )
    return np.where(crossing | inside, 0.0, near)
