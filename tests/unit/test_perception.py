"""The obstacle detector's clusters, on a scan built by hand: where each is, how big, what kind,
one cluster across the scan's seam, and another robot of the fleet known as a robot."""

from __future__ import annotations

import math

import numpy as np

from astiop.sim.lidar import LidarSpec
from astiop.sim.perception import detect


def test_clusters_sizes_kinds_and_the_seam():
    spec = LidarSpec()
    angles = spec.beam_angles()
    ranges = np.full(spec.beams, np.inf)
    unmapped = np.zeros(spec.beams, dtype=bool)
    robots = np.full(spec.beams, -1)
    person, robot, seam = range(200, 205), range(250, 281), [358, 359, 0, 1]
    ranges[list(person)] = 3.0
    ranges[list(robot)] = 2.0
    ranges[seam] = 4.0
    ranges[[300, 301]] = 5.0  # on the map: never an obstacle
    for beams in (person, robot, seam):
        unmapped[list(beams)] = True
    robots[list(robot)] = 3
    found = detect(ranges, unmapped, angles, (1.0, 2.0, 0.0), robots)
    assert [(o.kind, o.robot) for o in found] == [("robot", 3), ("person", -1), ("person", -1)]
    assert [o.distance for o in found] == [2.0, 3.0, 4.0]  # nearest first
    near = found[1]
    chord = 2 * 3.0 * math.sin(4 * spec.angle_increment / 2)  # five beams, four gaps
    assert abs(near.size - chord) < 1e-9
    mid = angles[202]
    assert abs(near.x - (1.0 + 3.0 * math.cos(mid))) < 0.01
    assert abs(near.y - (2.0 + 3.0 * math.sin(mid))) < 0.01
    back = found[2]  # beams 358..1: one cluster behind the robot, not two
    assert abs(back.x - (1.0 - 4.0)) < 0.01 and abs(back.y - 2.0) < 0.1
    assert detect(ranges, np.zeros(spec.beams, dtype=bool), angles, (0, 0, 0)) == []
