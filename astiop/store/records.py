"""What the store hands out and the errors it raises."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


class StoreError(Exception):
    """The database file cannot be used; it is left untouched."""


class LocationError(ValueError):
    """A location request is invalid; nothing was changed."""


@dataclass(frozen=True)
class Location:
    name: str
    x: float
    y: float
    theta: float  # rad
    description: str = ""

    def as_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "x": round(self.x, 4),
            "y": round(self.y, 4),
            "theta_deg": round(math.degrees(self.theta), 3),
            "description": self.description,
        }


def location_of(row: dict[str, Any]) -> Location:
    return Location(row["name"], row["x"], row["y"], row["theta"], row["description"] or "")
