"""Several ASTIbots in one warehouse: bodies of one physics world, stepped by one clock.

Each robot is a `Simulator` of its own (its battery, goals, lidar, events and dock) sharing the
world and one lock: every robot's lidar sees the others, no two pass through each other (a
contact is a collision fault, as with a wall), and navigation waits for a robot in the way,
plans around it, or gives its goal up and says so (`Navigation._yield_to_robots`).
"""

from __future__ import annotations

import math
import threading
from dataclasses import replace

from astiop.sim.simulator import Simulator
from astiop.sim.world import World
from astiop.warehouse import Station, WarehouseMap, default_map

DOCK_SPACING_M = 1.0
WEST_DOCKS = 20  # along the west wall from the first dock north; then along the south wall


def dock_name(index: int) -> str:
    """The dock of robot `index` (0-based): the map's own for the first."""
    return "charging_dock" if index == 0 else f"charging_dock_{index + 1}"


def with_docks(warehouse: WarehouseMap, robots: int) -> WarehouseMap:
    """The map with a charging dock per robot: the first is the map's, the next ones 1 m apart
    along the west wall, then along the south wall, each a copy of the first turned to face
    its wall."""
    first = warehouse.station("charging_dock")
    if first is None or first.docked_pose is None:
        raise ValueError(f"the map '{warehouse.name}' has no charging dock to copy")
    docks = []
    for i in range(1, robots):
        if i < WEST_DOCKS:
            dy = i * DOCK_SPACING_M
            docks.append(_shifted(first, dock_name(i), 0.0, dy))
        else:
            docks.append(_south_dock(warehouse, first, dock_name(i), i - WEST_DOCKS))
    for dock in docks:
        if not warehouse.inside_bounds(*dock.pose[:2]):
            raise ValueError(f"{robots} robots do not fit the map's walls with a dock each")
    return replace(warehouse, stations=(*warehouse.stations, *docks))


def _shifted(st: Station, name: str, dx: float, dy: float) -> Station:
    x0, y0, x1, y1 = st.rect
    (px, py, pt), (qx, qy, qt) = st.pose, st.docked_pose
    return Station(
        name, st.kind, (x0 + dx, y0 + dy, x1 + dx, y1 + dy), (px + dx, py + dy, pt),
        (qx + dx, qy + dy, qt),
    )  # fmt: skip


def _south_dock(warehouse: WarehouseMap, st: Station, name: str, k: int) -> Station:
    """The west wall's dock turned a quarter onto the south wall, at x = 5 + k m: the same
    depth off the wall for its rectangle, its working pose and its docked pose."""
    x0, y0, x1, y1 = st.rect  # on the west wall: thin in x, long in y
    west_wall_x = x0
    south_wall_y = min(w[3] for w in warehouse.walls)  # the south wall's inner face
    cx, half = 5.0 + k * DOCK_SPACING_M, (y1 - y0) / 2
    rect = (cx - half, south_wall_y, cx + half, south_wall_y + (x1 - x0))
    off = st.pose[0] - west_wall_x
    docked_off = st.docked_pose[0] - west_wall_x
    facing = -math.pi / 2
    return Station(
        name, st.kind, rect, (cx, south_wall_y + off, facing),
        (cx, south_wall_y + docked_off, facing),
    )  # fmt: skip


class SimFleet:
    """ASTIbots named `names`, each starting docked at its own dock (or at `starts[i]`)."""

    def __init__(
        self,
        names: list[str],
        *,
        seed: int = 0,
        warehouse: WarehouseMap | None = None,
        starts: list | None = None,
        **kw,
    ):
        if not names:
            raise ValueError("a fleet has at least one robot")
        self.map = with_docks(warehouse or default_map(), len(names))
        self.world = World(self.map)
        self.lock = threading.RLock()
        self.robots = [
            Simulator(
                self.map, seed=seed + i, world=self.world, lock=self.lock, dock=dock_name(i),
                name=name, start=starts[i] if starts else None, **kw,
            )
            for i, name in enumerate(names)
        ]  # fmt: skip
        for i, a in enumerate(self.robots):
            for b in self.robots[i + 1 :]:
                self.world.space.on_collision(
                    a.shape.collision_type,
                    b.shape.collision_type,
                    begin=self._on_contact,
                    post_solve=self._on_depth,
                )
        self._by_shape = {r.shape: r for r in self.robots}
        self.dt = self.robots[0].dt
        self._carry = 0.0
        self.after_step: list = []

    @property
    def t(self) -> float:
        return self.robots[0].t

    def step(self, duration: float) -> None:
        with self.lock:
            self._carry += duration
            n = int(self._carry / self.dt + 1e-9)
            self._carry -= n * self.dt
            for _ in range(n):
                for robot in self.robots:
                    robot.physics.before_world_step()
                self.world.step(self.dt)
                for robot in self.robots:
                    robot.physics.after_world_step()
        for observe in self.after_step:
            observe()

    def _on_contact(self, arbiter, space, data) -> None:
        a, b = (self._by_shape[s] for s in arbiter.shapes)
        a.physics.contact, b.physics.contact = b.shape.kind, a.shape.kind

    def _on_depth(self, arbiter, space, data) -> None:
        for robot in (self._by_shape[s] for s in arbiter.shapes):
            robot.physics.on_depth(arbiter, space, data)
