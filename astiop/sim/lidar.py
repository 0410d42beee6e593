"""360° LiDAR (LsLiDAR M10: 10 Hz, 25 m, ±3 cm) cast against the world's edges at once.

Only edges facing the sensor are kept, and each edge is intersected only with the beams in its
angular span, so a scan costs a few thousand ray-segment tests, not beams × edges.

`cast` is the plain statement of it; `cast_edges` is the same arithmetic on edges prepared
once (`Edges`), in fewer numpy calls: a scan is ~1 k ray tests, so its cost is the number of
numpy calls, not the arithmetic. The two agree bit for bit (tests/unit/test_lidar_fast.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class LidarSpec:
    beams: int = 360
    range_min: float = 0.10
    range_max: float = 25.0
    rate_hz: float = 10.0
    noise_sigma: float = 0.01

    @property
    def angle_min(self) -> float:
        return -math.pi

    @property
    def angle_increment(self) -> float:
        return TWO_PI / self.beams

    def beam_angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.beams)


def cast(
    x: float, y: float, theta: float, a: np.ndarray, b: np.ndarray, spec: LidarSpec
) -> tuple[np.ndarray, np.ndarray]:
    """True ranges (inf where nothing within range) and the hit edge index (-1 for none)."""
    n = spec.beams
    ranges = np.full(n, np.inf)
    hit_edge = np.full(n, -1, dtype=np.int64)
    if len(a) == 0:
        return ranges, hit_edge
    e = b - a
    rel_a = a - (x, y)
    # front-facing: the sensor is on the outer side of the edge (outward normal = (ey, -ex))
    facing = (e[:, 1] * -rel_a[:, 0] - e[:, 0] * -rel_a[:, 1]) > 0
    idx = np.nonzero(facing)[0]
    if len(idx) == 0:
        return ranges, hit_edge
    ra, eb = rel_a[idx], e[idx]
    rb = ra + eb
    inc = spec.angle_increment
    base = theta + spec.angle_min
    ang_a = np.arctan2(ra[:, 1], ra[:, 0])
    ang_b = np.arctan2(rb[:, 1], rb[:, 0])
    # a facing edge is seen clockwise from a to b: its span runs from b to a counter-clockwise
    sweep = np.mod(ang_a - ang_b, TWO_PI)
    start = np.mod(ang_b - base, TWO_PI) / inc
    first = np.ceil(start - 1e-9).astype(np.int64)
    last = np.floor(start + sweep / inc + 1e-9).astype(np.int64)
    counts = np.maximum(last - first + 1, 0)
    total = int(counts.sum())
    if total == 0:
        return ranges, hit_edge
    edge_of_pair = np.repeat(np.arange(len(idx)), counts)
    offsets = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    beam = np.mod(first[edge_of_pair] + offsets, n)
    phi = base + beam * inc
    dx, dy = np.cos(phi), np.sin(phi)
    pa, pe = ra[edge_of_pair], eb[edge_of_pair]
    denom = dx * pe[:, 1] - dy * pe[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (pa[:, 0] * pe[:, 1] - pa[:, 1] * pe[:, 0]) / denom
    t = np.where((np.abs(denom) > 1e-12) & (t > 0), t, np.inf)
    # nearest hit per beam
    np.minimum.at(ranges, beam, t)
    won = np.isfinite(t) & (t == ranges[beam])
    hit_edge[beam[won]] = idx[edge_of_pair[won]]
    too_far = ranges > spec.range_max
    ranges[too_far] = np.inf
    hit_edge[too_far] = -1
    return ranges, hit_edge


def add_noise(ranges: np.ndarray, rng: np.random.Generator, spec: LidarSpec) -> np.ndarray:
    noisy = rng.normal(0.0, spec.noise_sigma, size=ranges.shape)
    noisy += ranges
    return np.maximum(noisy, spec.range_min, out=noisy)  # no NaN: the same as a masked set


class Edges:
    """Edges a lidar casts against, laid out once as contiguous columns ax, ay, ex, ey
    (e = b - a, as `cast` computes it): the fixed geometry's once per change of the world."""

    __slots__ = ("ax", "ay", "ex", "ey", "count")

    def __init__(self, a: np.ndarray, b: np.ndarray):
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        e = np.asarray(b, dtype=float).reshape(-1, 2) - a
        self.ax, self.ay = a[:, 0].copy(), a[:, 1].copy()
        self.ex, self.ey = e[:, 0].copy(), e[:, 1].copy()
        self.count = len(a)


class _Beams:
    """Per lidar spec: inf ranges and -1 hits to copy, each beam's angle from the first
    (`cast`'s beam * inc), beam indices mod n, and the last heading's beam directions (a base
    that keeps its heading, or stands, reuses them)."""

    __slots__ = ("no_ranges", "no_hits", "offsets", "wrap", "last")

    def __init__(self, spec: LidarSpec):
        n = spec.beams
        self.no_ranges = np.full(n, np.inf)
        self.no_hits = np.full(n, -1, dtype=np.int64)
        self.offsets = np.arange(n) * spec.angle_increment
        self.wrap = np.arange(2 * n + 1) % n  # beam j's index mod n, looked up: 0 <= j <= 2n
        self.last = (math.nan, self.no_ranges, self.no_ranges)

    def directions(self, base: float) -> tuple[np.ndarray, np.ndarray]:
        """cos and sin of each beam's angle, for a scan whose first beam is at `base`. Shared by
        the simulators of a process, whatever their threads: `last` is one tuple, read and
        replaced whole."""
        held, cos, sin = self.last
        if base != held:
            phi = base + self.offsets
            cos, sin = np.cos(phi), np.sin(phi)
            self.last = (base, cos, sin)
        return cos, sin


_BEAMS: dict[LidarSpec, _Beams] = {}
_COUNT = np.arange(1 << 15)  # a scan's edges and pairs are numbered from this (sliced)


def _count(n: int) -> np.ndarray:
    return _COUNT[:n] if n <= len(_COUNT) else np.arange(n)


def cast_edges(
    x: float, y: float, theta: float, edges: Edges, spec: LidarSpec, hits: bool = True
) -> tuple[np.ndarray, np.ndarray | None]:
    """`cast` on prepared edges: the same ranges and hit edges, bit for bit; no hit edges
    (None) with `hits=False`, for a world whose every edge is the map's.

    Why each step gives `cast`'s bits: the facing test's value ex·ry − ey·rx is `cast`'s
    (negation is exact) and minus the pair's numerator, computed once per edge as ey·rx − ex·ry;
    a beam's direction is cos/sin of the same angle, per beam instead of per pair; a facing
    edge's numerator is < 0, so `cast`'s "|denom| > 1e-12 and t > 0" is "denom < −1e-12"; a
    span's last beam is never before its first (sweep >= 0), so no count is clamped; and a hit
    (a finite t) never equals a range cut to inf beyond range_max, so no such beam is won.
    """
    beams = _BEAMS.get(spec) or _BEAMS.setdefault(spec, _Beams(spec))
    ranges, hit_edge = beams.no_ranges.copy(), beams.no_hits.copy() if hits else None
    if edges.count == 0:
        return ranges, hit_edge
    rx, ry = edges.ax - x, edges.ay - y
    numer = edges.ey * rx
    numer -= edges.ex * ry
    idx = (numer < 0).nonzero()[0]  # facing the sensor: it is on the edge's outer side
    if len(idx) == 0:
        return ranges, hit_edge
    rx, ry, ex, ey, numer = rx[idx], ry[idx], edges.ex[idx], edges.ey[idx], numer[idx]
    inc = spec.angle_increment
    base = theta + spec.angle_min
    span = np.empty((2, len(idx)))  # the sweep, then the start, in beams
    ang_b = np.arctan2(ry + ey, rx + ex)  # as `cast`: (a - p) + e
    np.subtract(np.arctan2(ry, rx), ang_b, out=span[0])
    np.subtract(ang_b, base, out=span[1])
    np.mod(span, TWO_PI, out=span)
    span /= inc
    sweep, start = span
    first = start - 1e-9
    np.ceil(first, out=first)
    counts = start + sweep
    counts += 1e-9
    np.floor(counts, out=counts)
    counts -= first
    counts += 1.0
    counts = counts.astype(np.int64)
    ends = counts.cumsum()
    total = int(ends[-1])
    if total == 0:
        return ranges, hit_edge
    edge_of_pair = _count(len(idx)).repeat(counts)
    # a pair's beam: its edge's first beam (<= n) + its rank among the edge's pairs (<= n), mod n
    shift = first.astype(np.int64)
    shift -= ends
    shift += counts
    beam = shift[edge_of_pair]
    beam += _count(total)
    beam = beams.wrap[beam]
    cos, sin = beams.directions(base)
    denom = cos[beam] * ey[edge_of_pair]
    denom -= sin[beam] * ex[edge_of_pair]
    # no hit where `cast` has none: NaN divides silently and is never a minimum (fmin)
    denom[denom >= -1e-12] = np.nan
    t = numer[edge_of_pair] / denom  # finite, or NaN
    np.fmin.at(ranges, beam, t)
    ranges[ranges > spec.range_max] = np.inf
    if not hits:
        return ranges, None
    won = t == ranges[beam]
    hit_edge[beam[won]] = idx[edge_of_pair[won]]
    return ranges, hit_edge
