"""The simulator's lidar fast path (`cast_edges` on prepared `Edges`) against the plain one
(`cast`): the same ranges and the same hit edges, bit for bit, in the warehouse with obstacles
and another robot, on grid-aligned poses (beams through corners) and on random segments."""

from __future__ import annotations

import math

import numpy as np
import pytest

from astiop.sim.fleet import SimFleet
from astiop.sim.lidar import Edges, LidarSpec, add_noise, cast, cast_edges
from astiop.sim.simulator import Simulator


def _same(x, y, theta, a, b, spec):
    want_ranges, want_hits = cast(x, y, theta, a, b, spec)
    ranges, hits = cast_edges(x, y, theta, Edges(a, b), spec)
    assert ranges.tobytes() == want_ranges.tobytes(), (x, y, theta)
    assert np.array_equal(hits, want_hits), (x, y, theta)
    only_ranges, none = cast_edges(x, y, theta, Edges(a, b), spec, hits=False)
    assert none is None and only_ranges.tobytes() == want_ranges.tobytes()


def test_the_warehouse_with_obstacles_bit_for_bit():
    sim = Simulator(seed=0)
    for kind, x, y, th in (("pallet", 10, 5, 0.0), ("person", 15, 8, 0.3), ("box", 8, 12, 0.6)):
        sim.add_obstacle(kind, x, y, th)
    a, b, _ = sim.world.edges(sim.body)
    x0, y0, x1, y1 = sim.map.bounds
    rng = np.random.default_rng(1)
    for i in range(1500):
        x, y, theta = rng.uniform(x0 - 1, x1 + 1), rng.uniform(y0 - 1, y1 + 1), rng.uniform(-7, 7)
        if i % 3 == 0:  # on the half-metre grid, headings a multiple of 45°: beams hit corners
            x, y, theta = round(x * 2) / 2, round(y * 2) / 2, int(rng.integers(-8, 9)) * math.pi / 4
        _same(x, y, theta, a, b, sim.lidar_spec)


@pytest.mark.parametrize("beams", [360, 90, 1000])
def test_random_segments_bit_for_bit(beams):
    spec = LidarSpec(beams=beams, range_max=8.0)
    rng = np.random.default_rng(beams)
    for i in range(400):
        m = int(rng.integers(0, 40))
        a = rng.uniform(-10, 10, (m, 2))
        b = a if i % 7 == 0 else a + rng.normal(0, 3, (m, 2))  # some degenerate edges
        _same(*rng.uniform(-5, 5, 2), rng.uniform(-4, 4), a, b, spec)


def test_a_fleet_robot_sees_the_others_as_the_plain_cast_does():
    fleet = SimFleet(["a", "b", "c"], seed=2)
    fleet.step(1.0)
    for robot in fleet.robots:
        edges, owners, unmapped = fleet.world.lidar_edges(robot.body)
        a, b, want_owners = fleet.world.edges(robot.body)
        assert unmapped and np.array_equal(owners, want_owners)
        x, y, theta = robot.pose
        want = cast(x, y, theta, a, b, robot.lidar_spec)
        got = cast_edges(x, y, theta, edges, robot.lidar_spec)
        assert got[0].tobytes() == want[0].tobytes() and np.array_equal(got[1], want[1])


def test_the_simulator_scans_as_with_the_plain_cast():
    """A seeded run scans the same with the fast path as with `cast` and its masked noise."""

    def run(plain: bool):
        sim = Simulator(seed=5)
        if plain:
            import astiop.sim.simulator as module

            def slow(x, y, theta, edges, spec, hits=True):
                a, b, _ = sim.world.edges(sim.body)
                return cast(x, y, theta, a, b, spec)

            sim_cast = module.lidar.cast_edges
            module.lidar.cast_edges = slow
        try:
            sim.add_obstacle("pallet", 6.0, 4.0)
            sim.goto(*sim.map.station("assembly_station").pose)
            scans = []
            for _ in range(30):
                sim.step(0.5)
                scans.append(sim.scan_ranges.copy())
            return np.array(scans), sim.pose, [d.bbox for d in sim.detected]
        finally:
            if plain:
                module.lidar.cast_edges = sim_cast

    fast, plain = run(False), run(True)
    assert fast[0].tobytes() == plain[0].tobytes()
    assert fast[1:] == plain[1:]


def test_the_noise_is_the_masked_sum_it_was():
    spec = LidarSpec()
    ranges = np.concatenate([np.linspace(0.0, 30.0, 300), np.full(60, np.inf)])
    want = ranges + np.random.default_rng(4).normal(0.0, spec.noise_sigma, size=ranges.shape)
    want[want < spec.range_min] = spec.range_min
    got = add_noise(ranges, np.random.default_rng(4), spec)
    assert got.tobytes() == want.tobytes()
