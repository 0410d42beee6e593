"""`astiop sim bench`: a seeded mission run as fast as possible, with its figures."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

from astiop.sim.simulator import Simulator

MISSION = ("undock", "assembly_station", "cps_storage", "shipping", "dock")


@dataclass
class BenchFigures:
    real_time_factor: float
    lidar_ms_mean: float
    plan_ms_mean: float
    plan_ms_max: float
    mission_sim_s: float
    mission_wall_s: float
    max_penetration_m: float
    reached_all: bool
    legs: list[dict]

    def as_json(self) -> dict:
        return asdict(self)


def run_mission(seed: int = 0, on_leg: Callable[[str, dict], None] | None = None) -> BenchFigures:
    sim = Simulator(seed=seed)
    legs: list[dict] = []
    wall0 = time.perf_counter()
    for step in MISSION:
        if step == "undock":
            sim.undock()
        elif step == "dock":
            sim.dock()
        else:
            x, y, th = sim.map.station(step).pose
            sim.goto(x, y, th, step)
        t0 = sim.t
        result = sim.run_goal(900.0)
        leg = {
            "goal": step,
            "status": result.status if result else "none",
            "sim_s": round(sim.t - t0, 2),
            "error_m": round(result.error_m, 4) if result else None,
        }
        legs.append(leg)
        if on_leg:
            on_leg(step, leg)
    wall = time.perf_counter() - wall0
    return BenchFigures(
        real_time_factor=sim.t / wall,
        lidar_ms_mean=statistics.fmean(sim.lidar_ms),
        plan_ms_mean=statistics.fmean(sim.plan_ms),
        plan_ms_max=max(sim.plan_ms),
        mission_sim_s=sim.t,
        mission_wall_s=wall,
        max_penetration_m=sim.max_penetration,
        reached_all=all(leg["status"] == "succeeded" for leg in legs),
        legs=legs,
    )
