"""A map's zones as Nav2's own costmap filter masks: a keepout mask and a speed mask, each a PGM
and the YAML nav2_map_server loads it by, and the parameters of the `costmap_filter_info_server`
that announces each (its `CostmapFilterInfo`: type, mask topic, base, multiplier).

Read from ros-navigation/navigation2, branches humble and jazzy (the same on both):
- nav2_map_server/src/map_io.cpp: `mode: raw` takes a pixel's grey value as the cell's
  occupancy itself (0..100; anything else is unknown, -1); image row 0 is the map's top (its
  largest y); `resolution`, `origin`, `negate`, `occupied_thresh`, `free_thresh` are required.
- nav2_map_server/src/map_server/map_server.cpp: `yaml_filename`, `topic_name`, `frame_id`.
- nav2_map_server/src/costmap_filter_info/costmap_filter_info_server.cpp: `filter_info_topic`,
  `type`, `mask_topic`, `base`, `multiplier`.
- nav2_costmap_2d/include/nav2_costmap_2d/costmap_filters/filter_values.hpp: type 0 is
  KEEPOUT_FILTER, 2 SPEED_FILTER_ABSOLUTE; a speed mask's 0 is "no limit", -1 unknown.
- nav2_costmap_2d/plugins/costmap_filters/costmap_filter.cpp (getMaskCost): a mask value of
  100 becomes LETHAL_OBSTACLE in the keepout filter; speed_filter.cpp: the limit is
  `base + multiplier * value` for a value in 1..100.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yaml

from astiop.zones import MapZone, points_in_polygon

KEEPOUT_FILTER, SPEED_FILTER_ABSOLUTE = 0, 2
KEEPOUT_VALUE = 100  # OCC_GRID_OCCUPIED: lethal in the keepout filter
FREE_VALUE = 0  # free (keepout), no limit (speed)
DEFAULT_RESOLUTION = 0.05  # m per pixel, as Nav2's own maps


def speed_multiplier(zones: Sequence[MapZone]) -> float:
    """m/s per mask step: 0.01 (1 cm/s) unless a limit needs more than 100 steps."""
    fastest = max((z.speed or 0.0 for z in zones if z.kind == "speed"), default=0.0)
    return max(0.01, fastest / 100)


def masks(
    zones: Sequence[MapZone],
    bounds: tuple[float, float, float, float],
    resolution: float = DEFAULT_RESOLUTION,
) -> dict[str, np.ndarray]:
    """{"keepout": rows, "speed": rows}: uint8 images, row 0 the top (largest y)."""
    x0, y0, x1, y1 = bounds
    width = max(1, round((x1 - x0) / resolution))
    height = max(1, round((y1 - y0) / resolution))
    xs = x0 + (np.arange(width) + 0.5) * resolution
    ys = y0 + (height - np.arange(height) - 0.5) * resolution  # row 0: the top
    gx, gy = np.meshgrid(xs, ys)
    keepout = np.full((height, width), FREE_VALUE, dtype=np.uint8)
    speed = np.full((height, width), FREE_VALUE, dtype=np.uint8)
    step = speed_multiplier(zones)
    for zone in zones:
        inside = points_in_polygon(gx, gy, zone.corners)
        if zone.kind == "keepout":
            keepout[inside] = KEEPOUT_VALUE
        else:
            value = max(1, min(100, round(zone.speed / step)))
            # two speed zones overlapping: the lower limit wins, as safety's does
            lower = inside & ((speed == FREE_VALUE) | (speed > value))
            speed[lower] = value
    return {"keepout": keepout, "speed": speed}


def _write_pgm(path: Path, image: np.ndarray) -> None:
    height, width = image.shape
    path.write_bytes(f"P5\n{width} {height}\n255\n".encode() + image.tobytes())


def read_pgm(path: Path) -> np.ndarray:
    """A binary PGM (P5, maxval 255) as written here: its rows, top first."""
    data = path.read_bytes()
    fields, at = [], 0
    while len(fields) < 4:
        while data[at : at + 1].isspace():
            at += 1
        end = at
        while not data[end : end + 1].isspace():
            end += 1
        fields.append(data[at:end])
        at = end
    magic, width, height, _ = fields
    if magic != b"P5":
        raise ValueError(f"{path} is not a binary PGM")
    w, h = int(width), int(height)
    return np.frombuffer(data[at + 1 : at + 1 + w * h], dtype=np.uint8).reshape(h, w)


def export(
    zones: Sequence[MapZone],
    bounds: tuple[float, float, float, float],
    folder: Path,
    resolution: float = DEFAULT_RESOLUTION,
    frame_id: str = "map",
) -> list[Path]:
    """Write the masks, their YAML and the servers' parameters into `folder`; the files."""
    folder.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    params: dict = {}
    step = speed_multiplier(zones)
    for kind, image in masks(zones, bounds, resolution).items():
        pgm, meta = folder / f"{kind}_mask.pgm", folder / f"{kind}_mask.yaml"
        _write_pgm(pgm, image)
        meta.write_text(
            yaml.safe_dump(
                {
                    "image": pgm.name,
                    "mode": "raw",
                    "resolution": resolution,
                    "origin": [bounds[0], bounds[1], 0.0],
                    "negate": 0,
                    "occupied_thresh": 0.65,
                    "free_thresh": 0.196,
                },
                sort_keys=False,
            ),
            encoding="utf-8",
        )
        written += [pgm, meta]
        topic = f"/{kind}_filter_mask"
        params[f"{kind}_filter_info_server"] = {
            "ros__parameters": {
                "filter_info_topic": f"/{kind}_costmap_filter_info",
                "type": KEEPOUT_FILTER if kind == "keepout" else SPEED_FILTER_ABSOLUTE,
                "mask_topic": topic,
                "base": 0.0,
                "multiplier": 1.0 if kind == "keepout" else step,
            }
        }
        params[f"{kind}_mask_server"] = {
            "ros__parameters": {
                "yaml_filename": str(meta.resolve()),
                "topic_name": topic,
                "frame_id": frame_id,
            }
        }
    out = folder / "costmap_filter_info.yaml"
    out.write_text(yaml.safe_dump(params, sort_keys=False), encoding="utf-8")
    return [*written, out]
