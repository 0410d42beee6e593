"""The base's lidar and obstacle detector, at 10 Hz: the last scan, when it was made, and the
obstacles found in it."""

from __future__ import annotations

import collections
import time

import numpy as np

from astiop.sim import lidar
from astiop.sim.base import Base
from astiop.sim.clock import Clock
from astiop.sim.perception import DetectedObstacle, detect
from astiop.sim.world import ROBOT_OWNER, World


class Scanner:
    def __init__(
        self,
        world: World,
        base: Base,
        clock: Clock,
        spec: lidar.LidarSpec,
        rng: np.random.Generator,
    ) -> None:
        self.world = world
        self.base = base
        self.clock = clock
        self.spec = spec
        self.rng = rng  # the range noise's
        self.beam_angles = spec.beam_angles()
        self.ranges = np.full(spec.beams, np.inf)
        self.stamp = 0.0  # sim time of the last scan
        self.detected: list[DetectedObstacle] = []  # nearest first
        self.ms: collections.deque[float] = collections.deque(maxlen=2000)  # each cast's cost

    def scan(self) -> None:
        t0 = time.perf_counter()
        edges, owner, unmapped_edges = self.world.lidar_edges(self.base.body)
        x, y, th = self.base.pose
        ranges, hit = lidar.cast_edges(x, y, th, edges, self.spec, hits=unmapped_edges)
        self.ms.append((time.perf_counter() - t0) * 1e3)
        self.ranges = lidar.add_noise(ranges, self.rng, self.spec)
        self.stamp = self.clock.t
        if not unmapped_edges:  # every edge is the map's: nothing to detect
            self.detected = []
            return
        assert hit is not None  # asked for: some edge is not the map's
        owners = owner[np.maximum(hit, 0)]
        unmapped = (hit >= 0) & (owners >= 0)
        robots = None
        if len(self.world.robots) > 1:
            robots = np.where(unmapped & (owners >= ROBOT_OWNER), owners - ROBOT_OWNER, -1)
        self.detected = detect(self.ranges, unmapped, self.beam_angles, (x, y, th), robots)
