"""Where the map view writes its names (stations, zones, places, the fleet's robots): each where
it covers the fewest drawn cells and no other name. Pure numpy, no Textual."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class Name(NamedTuple):
    """A name to write next to a box (metres): a station, a zone (written inside), a place."""

    text: str
    box: tuple[float, float, float, float]
    inside: bool = False


def place_names(
    px: np.ndarray, frame, names: list[Name], floor: tuple[int, ...], marker: int
) -> dict[int, dict[int, str]]:
    """{cell row: {column: character}}; a name that fits nowhere is left out. `floor`: the
    pixel values a name may cover freely; `marker`: the value of drawn markers, avoided most."""
    s, x0, y0, top = frame
    rows, w = px.shape[0] // 2, px.shape[1]
    drawn = ~np.isin(px[0::2], floor) | ~np.isin(px[1::2], floor)
    markers = (px[0::2] == marker) | (px[1::2] == marker)
    taken = np.zeros((rows, w), dtype=bool)
    out: dict[int, dict[int, str]] = {}

    def cell(x: float, y: float) -> tuple[int, int]:
        return (top - 1 - math.floor((y - y0) * s)) // 2, math.floor((x - x0) * s)

    for name in names:
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
            cost = (int(drawn[r, c : c + n].sum()) + 4 * int(markers[r, c : c + n].sum()), order)
            if best is None or cost < best[0]:
                best = (cost, r, c)
        if best is None:
            continue
        _, r, c = best
        taken[r, c : c + n] = True
        out.setdefault(r, {}).update({c + i: ch for i, ch in enumerate(name.text)})
    return out
