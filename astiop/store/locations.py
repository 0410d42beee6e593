"""Named locations: each belongs to a map (the robot profile's), unique on it (case ignored),
inside the map's geofence."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Iterator
from contextlib import contextmanager

from astiop.bounded import has_controls
from astiop.store.connection import Connection
from astiop.store.records import Location, LocationError, location_of
from astiop.warehouse import fence_text, inside_fence

NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


DEFAULT_MAP = "warehouse"  # the simulator's, where the seeded places are


class LocationTables(Connection):
    map_name: str = DEFAULT_MAP  # the map this store's places are read from and saved on
    bounds: tuple[float, float, float, float] | None = None  # its geofence, when known

    def use_map(self, name: str, bounds: tuple[float, float, float, float] | None) -> None:
        """The robot's map: its places are the ones listed, found and saved from now on."""
        self.map_name, self.bounds = name or DEFAULT_MAP, bounds

    # -- locations ----------------------------------------------------------------
    def list_locations(self) -> list[Location]:
        rows = self.db.query(
            "SELECT * FROM locations WHERE map = ? ORDER BY name COLLATE NOCASE", [self.map_name]
        )
        return [location_of(r) for r in rows]

    def other_maps(self) -> dict[str, int]:
        """How many places each other map holds (said where this map has none)."""
        rows = self.db.conn.execute(
            "SELECT map, COUNT(*) FROM locations WHERE map != ? GROUP BY map", [self.map_name]
        ).fetchall()
        return dict(rows)

    def copy_locations_from(self, other: LocationTables) -> None:
        """This store's named locations become another's (a replay's or a bench run's own)."""
        rows = list(other.db.query("SELECT * FROM locations"))
        with self._tx():
            self.db.execute("DELETE FROM locations")
            if rows:
                self.db.table("locations").insert_all(rows)

    def get_location(self, name: str) -> Location | None:
        rows = list(
            self.db.query(
                "SELECT * FROM locations WHERE map = ? AND name = ? COLLATE NOCASE",
                [self.map_name, name],
            )
        )
        return location_of(rows[0]) if rows else None

    def require_location(self, name: str) -> Location:
        loc = self.get_location(name)
        if loc is None:
            known = ", ".join(loc.name for loc in self.list_locations()) or "none"
            raise LocationError(
                f"no location named '{name}' on the map {self.map_name} (known: {known})"
            )
        return loc

    def _check_new_name(self, name: str) -> None:
        if not NAME_RE.match(name):
            raise LocationError(
                f"invalid location name '{name}': use 1-64 letters, digits, '_' or '-'"
            )
        if self.get_location(name) is not None:
            raise LocationError(_exists(name))

    def _check_pose(self, x: float, y: float, theta: float) -> None:
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise LocationError("x, y and theta must be finite numbers")
        if self.bounds is not None and not inside_fence(self.bounds, x, y):
            raise LocationError(
                f"({x:g}, {y:g}) is outside the geofence ({fence_text(self.bounds)})"
            )

    def add_location(
        self, name: str, x: float, y: float, theta: float = 0.0, description: str = ""
    ) -> Location:
        self._check_new_name(name)
        self._check_pose(x, y, theta)
        if has_controls(description) or len(description) > 500:
            raise LocationError("a description is plain text of at most 500 characters")
        theta = math.atan2(math.sin(theta), math.cos(theta))
        now = time.time()
        with _said_exists(name), self._tx():  # another writer may have added it meanwhile
            self.db.table("locations").insert(
                {
                    "map": self.map_name,
                    "name": name,
                    "x": x,
                    "y": y,
                    "theta": theta,
                    "description": description,
                    "created_at": now,
                    "updated_at": now,
                }
            )
        return Location(name, x, y, theta, description)

    def rename_location(self, old: str, new: str) -> Location:
        loc = self.require_location(old)
        if new.lower() != loc.name.lower():
            self._check_new_name(new)
        elif not NAME_RE.match(new):
            raise LocationError(f"invalid location name '{new}'")
        with _said_exists(new), self._tx():
            self.db.conn.execute(
                "UPDATE locations SET name = ?, updated_at = ? "
                "WHERE map = ? AND name = ? COLLATE NOCASE",
                [new, time.time(), self.map_name, loc.name],
            )
        return Location(new, loc.x, loc.y, loc.theta, loc.description)

    def move_location(self, name: str, to_map: str) -> Location:
        """A place of this map moved to another (one saved on the wrong map)."""
        loc = self.require_location(name)
        if not to_map or to_map == self.map_name:
            raise LocationError(f"'{loc.name}' is on the map {self.map_name} already")
        here = self.map_name
        try:
            self.map_name = to_map  # its name must be free there
            if self.get_location(loc.name) is not None:
                raise LocationError(f"the map {to_map} has a place named '{loc.name}' already")
        finally:
            self.map_name = here
        with self._tx():
            self.db.conn.execute(
                "UPDATE locations SET map = ?, updated_at = ? "
                "WHERE map = ? AND name = ? COLLATE NOCASE",
                [to_map, time.time(), here, loc.name],
            )
        return loc

    def remove_location(self, name: str) -> Location:
        loc = self.require_location(name)
        with self._tx():
            self.db.conn.execute(
                "DELETE FROM locations WHERE map = ? AND name = ? COLLATE NOCASE",
                [self.map_name, loc.name],
            )
        return loc


def _exists(name: str) -> str:
    return f"a location named '{name}' already exists (names ignore case)"


@contextmanager
def _said_exists(name: str) -> Iterator[None]:
    """A duplicate found by the database (another writer was first): said as the check says."""
    try:
        yield
    except LocationError as exc:
        if "already exists" in str(exc):
            raise LocationError(_exists(name)) from None
        raise
