"""The warehouse map from `data/warehouse.yaml`: plain geometry, no physics."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import yaml

from astiop.resources import data_path

Rect = tuple[float, float, float, float]  # x_min, y_min, x_max, y_max


GEOFENCE_MARGIN = 0.5  # m kept clear of the walls: no goal, no named location closer


def inside_fence(bounds: Rect, x: float, y: float, margin: float = GEOFENCE_MARGIN) -> bool:
    """The one geofence test: goals (safety) and named locations (store) both use it."""
    x0, y0, x1, y1 = bounds
    return x0 + margin <= x <= x1 - margin and y0 + margin <= y <= y1 - margin


def fence_text(bounds: Rect, margin: float = GEOFENCE_MARGIN) -> str:
    x0, y0, x1, y1 = bounds
    return f"x {x0 + margin:g}..{x1 - margin:g}, y {y0 + margin:g}..{y1 - margin:g} m"


@dataclass(frozen=True)
class Station:
    name: str
    kind: str  # dock | conveyor
    rect: Rect
    pose: tuple[float, float, float]  # x, y, theta (rad)
    docked_pose: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Zone:
    name: str
    rect: Rect


@dataclass(frozen=True)
class WarehouseMap:
    name: str
    bounds: Rect
    walls: tuple[Rect, ...]
    shelves: tuple[Rect, ...]
    pillars: tuple[Rect, ...]
    stations: tuple[Station, ...]
    zones: tuple[Zone, ...] = field(default_factory=tuple)

    @property
    def static_rects(self) -> tuple[tuple[str, Rect], ...]:
        """Every fixed obstacle with its kind, in a stable order."""
        rects = [("wall", r) for r in self.walls]
        rects += [("shelf", r) for r in self.shelves]
        rects += [("pillar", r) for r in self.pillars]
        rects += [(f"station:{s.name}", s.rect) for s in self.stations]
        return tuple(rects)

    def inside_bounds(self, x: float, y: float) -> bool:
        x0, y0, x1, y1 = self.bounds
        return x0 <= x <= x1 and y0 <= y <= y1

    def station(self, name: str) -> Station | None:
        return next((s for s in self.stations if s.name == name.lower()), None)


def _rect(value: list[float], where: str) -> Rect:
    if not isinstance(value, list) or len(value) != 4:
        raise ValueError(f"{where}: a rectangle is [x_min, y_min, x_max, y_max]")
    x0, y0, x1, y1 = (float(v) for v in value)
    if x1 <= x0 or y1 <= y0:
        raise ValueError(f"{where}: empty rectangle {value}")
    return (x0, y0, x1, y1)


def _pose(value: list[float]) -> tuple[float, float, float]:
    x, y, theta_deg = (float(v) for v in value)
    return (x, y, math.radians(theta_deg))


def parse_map(data: dict) -> WarehouseMap:
    stations = tuple(
        Station(
            name=s["name"],
            kind=s.get("kind", "conveyor"),
            rect=_rect(s["rect"], f"station {s['name']}"),
            pose=_pose(s["pose"]),
            docked_pose=_pose(s["docked_pose"]) if s.get("docked_pose") else None,
        )
        for s in data.get("stations", [])
    )
    return WarehouseMap(
        name=data.get("name", "warehouse"),
        bounds=_rect(data["bounds"], "bounds"),
        walls=tuple(_rect(r, "wall") for r in data.get("walls", [])),
        shelves=tuple(_rect(r, "shelf") for r in data.get("shelves", [])),
        pillars=tuple(_rect(r, "pillar") for r in data.get("pillars", [])),
        stations=stations,
        zones=tuple(Zone(z["name"], _rect(z["rect"], z["name"])) for z in data.get("zones", [])),
    )


@lru_cache(maxsize=1)
def default_map() -> WarehouseMap:
    return parse_map(yaml.safe_load(data_path("warehouse.yaml").read_text(encoding="utf-8")))
