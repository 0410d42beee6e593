"""The warehouse as a pymunk space: fixed geometry, movable obstacles, and their lidar edges."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import pymunk

from astiop.sim.geometry import circle_polygon, oriented_box, polygon_edges, rect_edges
from astiop.sim.lidar import Edges
from astiop.warehouse import WarehouseMap

CT_ROBOT, CT_STATIC, CT_OBSTACLE = 1, 2, 3
CT_MORE_ROBOTS = 100  # the second robot of a world and on: one collision type each
ROBOT_OWNER = 1_000_000  # a lidar edge's owner id from here on is a robot's (its index added)

# kind -> (length, width) of a box, or (diameter, 0) of a round obstacle
OBSTACLE_SIZES: dict[str, tuple[float, float]] = {
    "pallet": (1.2, 0.8),
    "person": (0.6, 0.0),
    "forklift": (2.4, 1.2),
    "box": (0.6, 0.6),
}


class WorldError(ValueError):
    """A request about the world's contents is invalid."""


@dataclass(frozen=True)
class Obstacle:
    id: int
    kind: str
    x: float
    y: float
    theta: float

    def outline(self) -> np.ndarray:
        length, width = OBSTACLE_SIZES[self.kind]
        if width == 0.0:
            return circle_polygon(self.x, self.y, length / 2)
        return oriented_box(self.x, self.y, self.theta, length, width)


class World:
    def __init__(self, warehouse: WarehouseMap):
        self.map = warehouse
        self.space = pymunk.Space()
        self.space.iterations = 20
        self.static_kinds: list[str] = []
        a_list, b_list = [], []
        for kind, rect in warehouse.static_rects:
            x0, y0, x1, y1 = rect
            shape = pymunk.Poly(self.space.static_body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
            shape.collision_type = CT_STATIC
            shape.friction = 0.6
            shape.kind = kind
            self.space.add(shape)
            a, b = rect_edges(rect)
            a_list.append(a)
            b_list.append(b)
            self.static_kinds += [kind] * 4
        self._static_a = np.concatenate(a_list)
        self._static_b = np.concatenate(b_list)
        self.static_boxes = np.array([r for _, r in warehouse.static_rects], dtype=float)
        self.obstacles: dict[int, Obstacle] = {}
        self._obstacle_bodies: dict[int, tuple[pymunk.Body, pymunk.Shape]] = {}
        self._ids = itertools.count(1)
        self._edges_cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._lidar_cache: tuple[Edges, np.ndarray, bool] | None = None  # of the fixed edges
        self.robots: list[tuple[pymunk.Body, float, float, object]] = []  # … length, width, sim
        self.steps = 0  # physics steps so far: the robots' edges are computed once per step
        self._robot_edges: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None

    def step(self, dt: float) -> None:
        self.space.step(dt)
        self.steps += 1

    def add_robot(self, pose, mass: float, length: float, width: float, sim: object = None):
        """The robot's box body, led by a kinematic body through two joints with bounded force
        (the base's motors): a wall stops it instead of being pushed through. The first robot
        has collision type CT_ROBOT, each further one a type of its own (CT_MORE_ROBOTS on).
        Returns (control, body, shape)."""
        self.space.collision_slop = 0.002
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body = pymunk.Body(mass, pymunk.moment_for_box(mass, (length, width)))
        body.position = control.position = pose[:2]
        body.angle = control.angle = pose[2]
        hl, hw = length / 2, width / 2
        shape = pymunk.Poly(body, [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw)])
        shape.collision_type = CT_MORE_ROBOTS + len(self.robots) - 1 if self.robots else CT_ROBOT
        shape.friction = 0.5
        shape.kind = f"robot {getattr(sim, 'name', 'robot')}"
        self.robots.append((body, length, width, sim))
        pivot = pymunk.PivotJoint(control, body, (0, 0), (0, 0))
        pivot.max_bias, pivot.max_force = 0.0, 1500.0
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        gear.max_bias, gear.max_force = 0.0, 1500.0
        self.space.add(control, body, shape, pivot, gear)
        return control, body, shape

    def add_obstacle(self, kind: str, x: float, y: float, theta: float = 0.0) -> Obstacle:
        if kind not in OBSTACLE_SIZES:
            raise WorldError(f"unknown obstacle kind '{kind}' (one of {', '.join(OBSTACLE_SIZES)})")
        if not self.map.inside_bounds(x, y):
            raise WorldError(f"({x:.2f}, {y:.2f}) is outside the warehouse")
        obstacle = Obstacle(next(self._ids), kind, x, y, theta)
        body = pymunk.Body(body_type=pymunk.Body.STATIC)
        length, width = OBSTACLE_SIZES[kind]
        if width == 0.0:
            body.position = (x, y)
            shape: pymunk.Shape = pymunk.Circle(body, length / 2)
        else:
            shape = pymunk.Poly(body, [tuple(p) for p in oriented_box(0, 0, 0, length, width)])
            body.position, body.angle = (x, y), theta
        shape.collision_type = CT_OBSTACLE
        shape.kind = kind
        self.space.add(body, shape)
        self.obstacles[obstacle.id] = obstacle
        self._obstacle_bodies[obstacle.id] = (body, shape)
        self._edges_cache = self._lidar_cache = None
        return obstacle

    def remove_obstacle(self, obstacle_id: int) -> Obstacle:
        if obstacle_id not in self.obstacles:
            raise WorldError(f"no obstacle with id {obstacle_id}")
        body, shape = self._obstacle_bodies.pop(obstacle_id)
        self.space.remove(body, shape)
        self._edges_cache = self._lidar_cache = None
        return self.obstacles.pop(obstacle_id)

    def robot_rank(self, body: pymunk.Body) -> int:
        """The order in which this robot was added to the world, from 0."""
        return next(i for i, r in enumerate(self.robots) if r[0] is body)

    def edges(self, seen_by: pymunk.Body | None = None) -> tuple[np.ndarray, ...]:
        """All edges a lidar sees, with an owner per edge: -1 fixed geometry, an obstacle's id,
        or ROBOT_OWNER + a robot's index for the other robots of the world (not `seen_by`)."""
        fixed = self._fixed_edges()
        if len(self.robots) < 2 and (not self.robots or self.robots[0][0] is seen_by):
            return fixed
        a, b, owners = self._every_robots_edges()
        keep = owners != ROBOT_OWNER + self.robot_rank(seen_by) if seen_by else slice(None)
        return (
            np.concatenate([fixed[0], a[keep]]),
            np.concatenate([fixed[1], b[keep]]),
            np.concatenate([fixed[2], owners[keep]]),
        )

    def lidar_edges(self, seen_by: pymunk.Body | None = None) -> tuple[Edges, np.ndarray, bool]:
        """`edges(seen_by)` prepared for `lidar.cast_edges`: (edges, owners, whether any edge is
        not the fixed map's). The fixed geometry's are prepared once per change of it."""
        if len(self.robots) < 2 and (not self.robots or self.robots[0][0] is seen_by):
            if self._lidar_cache is None:
                a, b, owners = self._fixed_edges()
                self._lidar_cache = (Edges(a, b), owners, bool((owners >= 0).any()))
            return self._lidar_cache
        a, b, owners = self.edges(seen_by)
        return Edges(a, b), owners, bool((owners >= 0).any())

    def _every_robots_edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every robot's box edges as they are at this step, computed at once (a fleet's robots
        all scan the same step: once, not once per robot)."""
        if self._robot_edges is None or self._robot_edges[0] != self.steps:
            n = len(self.robots)
            pose = np.array([(*r[0].position, r[0].angle) for r in self.robots])
            half = np.array([(r[1] / 2, r[2] / 2) for r in self.robots])
            corners = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], dtype=float)  # CCW
            local = corners[None, :, :] * half[:, None, :]  # (n, 4, 2)
            c, s = np.cos(pose[:, 2])[:, None], np.sin(pose[:, 2])[:, None]
            x = local[..., 0] * c - local[..., 1] * s + pose[:, 0:1]
            y = local[..., 0] * s + local[..., 1] * c + pose[:, 1:2]
            pts = np.stack([x, y], axis=-1)  # (n, 4, 2): oriented_box's corners, at once
            a = pts.reshape(-1, 2)
            b = pts[:, [1, 2, 3, 0]].reshape(-1, 2)
            owners = np.repeat(ROBOT_OWNER + np.arange(n, dtype=np.int64), 4)
            self._robot_edges = (self.steps, a, b, owners)
        return self._robot_edges[1:]

    def _fixed_edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._edges_cache is None:
            a_parts, b_parts = [self._static_a], [self._static_b]
            owners = [np.full(len(self._static_a), -1, dtype=np.int64)]
            for ob in self.obstacles.values():
                a, b = polygon_edges(ob.outline())
                a_parts.append(a)
                b_parts.append(b)
                owners.append(np.full(len(a), ob.id, dtype=np.int64))
            self._edges_cache = (
                np.concatenate(a_parts),
                np.concatenate(b_parts),
                np.concatenate(owners),
            )
        return self._edges_cache

    def footprint_collides(
        self, x: float, y: float, theta: float, length: float, width: float, margin: float = 0.0
    ) -> str | None:
        """The kind of the first thing a robot footprint at this pose would overlap, if any."""
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position, body.angle = (x, y), theta
        box = oriented_box(0, 0, 0, length + 2 * margin, width + 2 * margin)
        probe = pymunk.Poly(body, [tuple(p) for p in box])
        for hit in self.space.shape_query(probe):
            if hit.shape.collision_type in (CT_STATIC, CT_OBSTACLE):
                return getattr(hit.shape, "kind", "obstacle")
        return None

    def nearest_station(self, x: float, y: float):
        best, best_d = None, math.inf
        for st in self.map.stations:
            d = math.hypot(st.pose[0] - x, st.pose[1] - y)
            if d < best_d:
                best, best_d = st, d
        return best, best_d
