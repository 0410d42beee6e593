"""The `multistep` suite's cases: a request of several steps on a seeded simulator, scored by the
paper's method extended by order. The ground truth is the simulator's: the named places where
the robot came to rest, in order, and whether it ended docked.

command: 100 when the places visited are exactly the expected ones in the expected order, the
docked state is right and a step that must fail failed; 50 when the visits begin right (some
steps done in order) but not all; 0 otherwise (a step out of order is wrong).
interpretation: 100 when nothing the answer and the mission's report claim is false (no place
reported reached that the robot did not reach) and a step that had to fail is reported failed.
"""

from __future__ import annotations

import asyncio
import math
import re

from astiop.agent.turn import Agent
from astiop.bench.suites import RobotCase
from astiop.missions import view
from astiop.missions.runner import MissionRunner
from astiop.sim.simulator import Simulator
from astiop.store import Store

AT_M = 0.3
STILL = 0.05
MISSION_WAIT_S = 600.0


class Visits:
    """Where the robot came to rest, at named places, in order (observed after each step)."""

    def __init__(self, sim: Simulator, places: dict[str, tuple[float, float]]):
        self.sim, self.places = sim, places
        self.seen: list[str] = []
        self.last = self._at()  # where it starts is not a visit

    def _at(self) -> str | None:
        x, y, _ = self.sim.pose
        return next((n for n, p in self.places.items() if math.dist((x, y), p) <= AT_M), None)

    def __call__(self) -> None:
        if self.sim.goal is not None or self.sim.speed() > STILL:
            return
        here = self._at()
        if here is not None and here != self.last:
            self.seen.append(here)
        if here is not None or math.dist(self.sim.pose[:2], self._last_xy()) > AT_M:
            self.last = here

    def _last_xy(self) -> tuple[float, float]:
        return self.places.get(self.last or "", (math.inf, math.inf))


def _prefix(got: list[str], want: list[str]) -> int:
    n = 0
    for a, b in zip(got, want, strict=False):
        if a != b:
            break
        n += 1
    return n


def score(case: RobotCase, visits: list[str], docked: bool, mission: dict | None, answer: str):
    want = [str(v) for v in case.outcome.get("visits", [])]
    fails = case.outcome.get("fails")
    checks = {"order": visits == want}
    if "docked" in case.outcome:
        checks["docked"] = docked == bool(case.outcome["docked"])
    if fails:
        failed = [s for s in (mission or {}).get("steps", []) if s["status"] == "failed"]
        checks["failed_step"] = any(str(fails) in s["label"] for s in failed)
    if all(checks.values()):
        command = 100.0
    elif _prefix(visits, want) > 0 or (not want and checks.get("docked", False)):
        command = 50.0
    else:
        command = 0.0
    claims = _claims(answer, mission, visits)
    if fails:
        claims["failure_reported"] = bool(
            re.search(
                rf"{re.escape(str(fails))}.*fail|fail.*{re.escape(str(fails))}", answer, re.I | re.S
            )
        )
    interpretation = 100.0 if all(claims.values()) else 0.0
    return command, interpretation, {"checks": checks, "claims": claims, "visits": visits}


def _claims(answer: str, mission: dict | None, visits: list[str]) -> dict[str, bool]:
    """Each place the report says was reached must have been reached."""
    said = re.findall(r"arrived: ([\w-]+)", answer)
    if mission is not None:
        said += [
            s["label"].removeprefix("go to ").split(": ")[-1].removeprefix("go to ")
            for s in mission["steps"]
            if s["status"] == "succeeded" and "go to" in s["label"]
        ]
    return {f"reached {p}": p in visits for p in dict.fromkeys(said) if not p.startswith("(")}


async def drive(store: Store, case: RobotCase, agent: Agent, sim: Simulator) -> tuple:
    """Run the request, wait for its mission (or goal) to end, and score it."""
    # the dock's station is where undocking leaves the robot: not a place a request visits
    places = {
        loc.name: (loc.x, loc.y) for loc in store.list_locations() if loc.name != "charging_dock"
    }
    visits = Visits(sim, places)
    sim.after_step.append(visits)
    runner = agent.missions
    assert runner is not None
    turn = await agent.turn(case.request)
    mission = None
    report = turn.answer
    if turn.mission_id is not None:
        await asyncio.to_thread(runner.wait, MISSION_WAIT_S)
        mission = view.as_json(store, turn.mission_id)
        if mission is not None:
            report += "\n" + view.done_text(mission)
    elif sim.goal is not None:
        await asyncio.to_thread(sim.run_goal, 600.0)
        report += "\n" + await agent.follow_up(turn, 5.0) if turn.started else ""
    visits()
    sim.after_step.remove(visits)
    command, interpretation, details = score(case, visits.seen, sim.docked(), mission, report)
    metrics = {
        "command": command,
        "interpretation": interpretation,
        "c_valid": command == 100.0,
        "i_valid": interpretation == 100.0,
        "total_s": turn.total_s,
        "ttft_s": turn.ttft_s,
        "tokens": turn.completion_tokens,
        "base": case.base or case.id,
        "wrong_actuations": 0,
        "refused": bool(turn.refused),
        "grounding": turn.grounding,
        "mission": None if mission is None else mission["status"],
        **details,
    }
    return "ok", metrics, report


def mission_agent(store: Store, config, endpoint, mode, gateway, case: RobotCase) -> Agent:
    runner = MissionRunner(gateway, store)
    runner.robot = f"bench-{case.id}"  # each case is its own simulated robot
    return Agent(
        gateway,
        endpoint,
        store,
        mode=mode,
        max_tokens=min(config.max_tokens, 160),
        confirm=lambda _c: True,
        confirm_mission=lambda _s, _f=False: True,
        fallback=False,
        interpretation=config.interpretation,
        missions=runner,
        session="bench",
    )
