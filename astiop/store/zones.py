"""Zones of a map (keepout, speed), stored with its places: each belongs to the map this store's
places are read from (`use_map`), its name unique there (case ignored), inside the map."""

from __future__ import annotations

import json
import time
from collections.abc import Sequence

from astiop.store.connection import Connection
from astiop.zones import MapZone, Point, ZoneError, check_zone


def _zone_of(row: dict) -> MapZone:
    corners = tuple((float(x), float(y)) for x, y in json.loads(row["corners"]))
    return MapZone(row["name"], row["kind"], corners, row["speed"])


class ZoneTables(Connection):
    map_name: str  # the map the zones are on and its fence: `LocationTables`'s
    bounds: tuple[float, float, float, float] | None

    def list_zones(self) -> list[MapZone]:
        rows = self.db.query(
            "SELECT * FROM zones WHERE map = ? ORDER BY name COLLATE NOCASE", [self.map_name]
        )
        return [_zone_of(r) for r in rows]

    def get_zone(self, name: str) -> MapZone | None:
        rows = list(
            self.db.query(
                "SELECT * FROM zones WHERE map = ? AND name = ? COLLATE NOCASE",
                [self.map_name, name],
            )
        )
        return _zone_of(rows[0]) if rows else None

    def require_zone(self, name: str) -> MapZone:
        zone = self.get_zone(name)
        if zone is None:
            known = ", ".join(z.name for z in self.list_zones()) or "none"
            raise ZoneError(f"no zone named '{name}' on the map {self.map_name} (known: {known})")
        return zone

    def add_zone(
        self, name: str, kind: str, corners: Sequence[Point], speed: float | None = None
    ) -> MapZone:
        zone = check_zone(name, kind, corners, speed, self.bounds)
        if (same := self.get_zone(name)) is not None:
            raise ZoneError(f"a zone named '{same.name}' already exists (names ignore case)")
        now = time.time()
        with self._tx():
            self.db.table("zones").insert(
                {
                    "map": self.map_name,
                    "name": zone.name,
                    "kind": zone.kind,
                    "corners": json.dumps([list(c) for c in zone.corners]),
                    "speed": zone.speed,
                    "created_at": now,
                    "updated_at": now,
                }
            )
        return zone

    def rename_zone(self, old: str, new: str) -> MapZone:
        zone = self.require_zone(old)
        check_zone(new, zone.kind, zone.corners, zone.speed, None)  # the name's rules
        same = self.get_zone(new)
        if new.lower() != zone.name.lower() and same is not None:
            raise ZoneError(f"a zone named '{same.name}' already exists (names ignore case)")
        with self._tx():
            self.db.conn.execute(
                "UPDATE zones SET name = ?, updated_at = ? WHERE map = ? AND name = ? COLLATE NOCASE",
                [new, time.time(), self.map_name, zone.name],
            )
        return MapZone(new, zone.kind, zone.corners, zone.speed)

    def remove_zone(self, name: str) -> MapZone:
        zone = self.require_zone(name)
        with self._tx():
            self.db.conn.execute(
                "DELETE FROM zones WHERE map = ? AND name = ? COLLATE NOCASE",
                [self.map_name, zone.name],
            )
        return zone
