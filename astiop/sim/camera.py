"""The robot's camera: a first-person view of the 2D warehouse, one ray per image column.

Each column's ray is cast against the world's edges that face the camera (the lidar's edges: the
map, the obstacles, the other robots); the nearest few hits are painted far to near, each as a
vertical span whose height on the image is its real height over its depth (a pinhole camera
with square pixels), over a floor and a ceiling shaded by distance. Colours follow the seed's
figures: the charging station green, the CPS storage red.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk

from astiop.sim.world import ROBOT_OWNER, World

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class CameraSpec:
    """The camera a simulated robot carries: its image, its rate and where it sits."""

    width: int = 160  # px
    height: int = 120  # px
    rate_hz: float = 5.0
    fov_deg: float = 60.0  # horizontal field of view
    mount_x: float = 0.45  # m ahead of the base's centre (tf_static: base_link -> camera)
    mount_z: float = 0.5  # m above the floor
    range_max: float = 30.0  # m: nothing is drawn beyond

    @property
    def focal_px(self) -> float:
        return (self.width / 2) / math.tan(math.radians(self.fov_deg) / 2)


ASTIBOT_CAMERA = CameraSpec()

# what each thing looks like: (colour, height in m)
LOOKS: dict[str, tuple[RGB, float]] = {
    "wall": ((196, 196, 188), 3.0),
    "shelf": ((176, 104, 16), 2.4),  # pallet racking, the map's racks' colour
    "pillar": ((232, 196, 40), 3.0),
    "station:charging_dock": ((40, 190, 70), 0.8),
    "station:cps_storage": ((214, 40, 40), 1.0),
    "station:assembly_station": ((150, 90, 200), 1.0),
    "station:shipping": ((238, 140, 30), 1.0),
    "station": ((120, 160, 160), 1.0),  # any other station
    "pallet": ((214, 178, 120), 1.1),  # loaded, light wood
    "person": ((255, 132, 0), 1.75),  # a hi-vis vest
    "forklift": ((245, 200, 0), 2.1),
    "box": ((150, 112, 70), 0.6),
    "robot": ((84, 88, 110), 0.7),
}
FLOOR: RGB = (118, 112, 100)
CEILING: RGB = (52, 58, 70)
LAYERS = 4  # hits painted per column: a low box before a rack before a wall


def look(kind: str) -> tuple[RGB, float]:
    if kind in LOOKS:
        return LOOKS[kind]
    return LOOKS["station"] if kind.startswith("station:") else LOOKS["box"]


def _shade(depth: np.ndarray) -> np.ndarray:
    """Light falls off with distance, never below a third."""
    return np.clip(1.0 / (1.0 + depth / 14.0), 0.33, 1.0)


class Camera:
    """Renders the view from a robot's pose; a frame is kept for its period of the sim clock."""

    def __init__(self, spec: CameraSpec = ASTIBOT_CAMERA):
        self.spec = spec
        w, h, f = spec.width, spec.height, spec.focal_px
        self._u = ((w / 2) - np.arange(w) - 0.5) / f  # a column's ray, left of the axis +
        self._rows = np.arange(h, dtype=float)[:, None] + 0.5
        self._background = self._floor_and_ceiling()
        self._static: tuple[np.ndarray, np.ndarray] | None = None  # per static edge
        self._static_of: World | None = None
        self._held: tuple[float, np.ndarray] | None = None
        self._view: tuple | None = None

    def _floor_and_ceiling(self) -> np.ndarray:
        s = self.spec
        img = np.empty((s.height, s.width, 3), dtype=np.float32)
        below = np.maximum(self._rows[:, 0] - s.height / 2, 1e-3)
        floor_depth = s.focal_px * s.mount_z / below  # where each row meets the floor
        floor = np.asarray(FLOOR, dtype=np.float32) * _shade(floor_depth)[:, None]
        up = np.clip(1.0 - self._rows[:, 0] / s.height, 0.0, 1.0)  # lighter toward the top
        ceiling = np.asarray(CEILING, dtype=np.float32) * (0.8 + 0.4 * up)[:, None]
        horizon = self._rows[:, 0] >= s.height / 2
        img[:] = np.where(horizon[:, None], floor, ceiling)[:, None, :]
        return img

    def _static_looks(self, world: World) -> tuple[np.ndarray, np.ndarray]:
        if self._static is None or self._static_of is not world:
            looks = [look(k) for k in world.static_kinds]
            colours = np.array([c for c, _ in looks], dtype=np.float32).reshape(-1, 3)
            heights = np.array([h for _, h in looks], dtype=float)
            self._static, self._static_of = (colours, heights), world
        return self._static

    def frame(self, world: World, body: pymunk.Body, t: float) -> tuple[float, np.ndarray]:
        """The frame of the period `t` falls in: (its time, RGB pixels (height, width, 3))."""
        at = math.floor(t * self.spec.rate_hz + 1e-9) / self.spec.rate_hz
        held = self._held
        if held is not None and held[0] == at:
            return held
        x, y = body.position
        theta = float(body.angle)
        a, b, owners = world.edges(seen_by=body)
        # the same pose and the very same edges array (kept, so its id is never another's): a
        # world that did not change
        view = (x, y, theta, a)
        last = self._view
        if held is not None and last is not None and last[:3] == view[:3] and last[3] is a:
            pixels = held[1]  # nothing moved: the same picture (a docked robot's, mostly)
        else:
            colours, heights = self._looks(world, owners)
            pixels = self.render((x, y, theta), a, b, colours, heights)
        self._held, self._view = (at, pixels), view
        return self._held

    def _looks(self, world: World, owners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        colours, heights = self._static_looks(world)
        more = owners[len(heights) :]
        if len(more) == 0:
            return colours, heights
        extra = [
            look("robot") if o >= ROBOT_OWNER else look(world.obstacles[int(o)].kind)
            for o in more.tolist()
        ]
        return (
            np.concatenate([colours, np.array([c for c, _ in extra], dtype=np.float32)]),
            np.concatenate([heights, np.array([h for _, h in extra], dtype=float)]),
        )

    def render(
        self,
        pose: tuple[float, float, float],
        a: np.ndarray,
        b: np.ndarray,
        colours: np.ndarray,
        heights: np.ndarray,
    ) -> np.ndarray:
        """The view from the camera on a base at `pose` of edges a -> b (counter-clockwise
        outlines), each with its colour and height."""
        s = self.spec
        x, y, theta = pose
        c, sn = math.cos(theta), math.sin(theta)
        px, py = x + s.mount_x * c, y + s.mount_x * sn
        e = b - a
        ra = a - (px, py)
        # the camera on the outer side of the edge (outward normal (ey, -ex)), as the lidar
        facing = np.nonzero(e[:, 1] * -ra[:, 0] + e[:, 0] * ra[:, 1] > 0)[0]
        img = self._background.copy()
        if len(facing):
            depth, hit = self._cast(c, sn, ra[facing], e[facing])
            self._paint(img, depth, colours[facing][hit], heights[facing][hit], e[facing][hit])
        return img.astype(np.uint8)

    def _cast(self, c: float, sn: float, ra: np.ndarray, e: np.ndarray):
        """Each column's nearest LAYERS hits, far to near: their depth along the camera's axis
        (inf: none) and the edge hit, both (width, layers)."""
        # a column's ray: forward + u * left, so its parameter is the depth along the axis
        dx = (c - self._u * sn)[:, None]
        dy = (sn + self._u * c)[:, None]
        ex, ey = e[:, 0][None, :], e[:, 1][None, :]
        ax, ay = ra[:, 0][None, :], ra[:, 1][None, :]
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ax * ey - ay * ex) / denom
            s = (ax * dy - ay * dx) / denom
        ok = (np.abs(denom) > 1e-12) & (s >= 0.0) & (s <= 1.0) & (t > 0.05)
        t = np.where(ok & (t <= self.spec.range_max), t, np.inf)
        k = min(LAYERS, t.shape[1])
        near = np.argpartition(t, k - 1, axis=1)[:, :k] if k < t.shape[1] else np.argsort(t, 1)
        depth = np.take_along_axis(t, near, axis=1)
        order = np.argsort(-depth, axis=1)  # far first; inf (no hit) first of all
        return np.take_along_axis(depth, order, 1), np.take_along_axis(near, order, 1)

    def _paint(self, img, depth, colours, heights, edges) -> None:
        s = self.spec
        f, mid = s.focal_px, s.height / 2
        across = np.abs(edges[..., 0]) < np.abs(edges[..., 1])  # faces east or west: darker
        light = _shade(np.where(np.isfinite(depth), depth, s.range_max)) * np.where(
            across, 0.8, 1.0
        )
        rows = self._rows
        for k in range(depth.shape[1]):
            d = depth[:, k]
            seen = np.isfinite(d)
            if not seen.any():
                continue
            dk = np.where(seen, d, 1.0)
            top = mid - f * (heights[:, k] - s.mount_z) / dk
            bottom = mid + f * s.mount_z / dk
            mask = (rows >= top[None, :]) & (rows < bottom[None, :]) & seen[None, :]
            colour = colours[:, k, :] * light[:, k, None]
            np.copyto(img, np.broadcast_to(colour[None, :, :], img.shape), where=mask[..., None])
