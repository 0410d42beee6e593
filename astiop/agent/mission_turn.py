"""A turn that starts a mission instead of sending its goals at once: the steps are reviewed
up front (nothing runs if one is invalid or unsafe), approved once as a whole, then handed to
the mission runner, which drives them one after the other after the turn has answered."""

from __future__ import annotations

import asyncio
import re
from collections.abc import Callable
from functools import partial
from typing import Any

from astiop.agent import gate, mission_plan
from astiop.agent.intent import Intent
from astiop.agent.result import TurnResult
from astiop.missions import view
from astiop.missions.runner import MissionError, MissionRunner
from astiop.missions.steps import Step, describe
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import Review
from astiop.store import Store

# (steps, repeated until stopped) -> approved
ConfirmMission = Callable[[list[Step], bool], bool]
# (the mission in the way, said; the new one's steps; repeated until stopped) -> replace it.
# True: replace without asking (astiop chat --replace); None or False: refuse.
ReplaceMission = Callable[[str, list[Step], bool], bool] | bool | None
GOAL_KINDS = ("navigate", "dock", "undock")


def plan_as_mission(
    request: str,
    commands: list[str],
    review: Callable[[str], Review],
    places: dict[str, tuple[float, float]],
) -> tuple[list[Step] | None, str | None]:
    """A model's plan that holds two or more goals is a mission: (steps, None), or (None, why
    it may not run), or (None, None) when the plan is not a mission."""
    actions = [gate.action_of(review(c).checked) for c in commands]
    if sum(a.kind in GOAL_KINDS for a in actions) < 2:
        return None, None
    return mission_plan.from_actions(request, actions, places)


def confirmer(
    confirm_mission: ConfirmMission | None,
    confirm: Callable | None,
    review: Callable[[str], Review],
) -> ConfirmMission | None:
    """How the operator approves a mission: as a whole where the caller can show it whole,
    else each distinct command that needs it, all asked before any runs; None: nobody can."""
    if confirm_mission is not None:
        return confirm_mission
    if confirm is None:
        return None

    def each(steps: list[Step], _forever: bool = False) -> bool:
        commands = dict.fromkeys(c for c in (s.command() for s in steps) if c)
        return all(confirm(review(c).checked) for c in commands if review(c).needs_confirmation)

    return each


def check_steps(steps: list[Step], review: Callable[[str], Review]) -> str | None:
    """Why the mission may not start (a step's command invalid or refused by safety)."""
    for n, step in enumerate(steps, 1):
        command = step.command()
        if command is None:
            continue
        r = review(command)
        # a named place the robot does not know is the robot's to refuse, as the step's end
        if not r.checked.valid or not r.allowed:
            return f"step {n} ({step.label()}): {r.reason or r.checked.reason}"
    return None


def start(
    gateway: RobotGateway,
    runner: MissionRunner,
    request: str,
    steps: list[Step],
    review: Callable[[str], Review],
    confirm: ConfirmMission | None,
    result: TurnResult,
    *,
    forever: bool = False,
    replace: ReplaceMission = None,
) -> str:
    """Start the mission; the turn's answer (started, or why not). A mission already running
    on the robot is replaced only if the operator says so (asked, or --replace)."""
    total = len(steps)
    plan = describe(steps, forever)
    why = check_steps(steps, review)
    if why is not None:
        result.refused = why
        return f"I did not start this mission: {why}. Nothing was sent to the robot. ({plan})"
    live = runner.live_mission()
    approved = False
    if live is not None:
        said = view.live_text(runner.store, live["id"])
        if replace is None or replace is False:
            result.refused = f"{said}: one mission per robot at a time"
            return (
                f"Mission not started: {said}. Replace it (astiop chat --replace) or cancel it "
                f"first (astiop mission cancel {live['id']}). Nothing was sent. ({plan})"
            )
        if callable(replace):
            if not replace(said, steps, forever):
                result.refused = f"mission {live['id']} not replaced, by the operator"
                return (
                    f"Mission not started: mission {live['id']} goes on, not replaced. "
                    f"Nothing was stored or sent. ({plan})"
                )
            approved = True  # the question showed every step of the new mission
    if not approved:
        if confirm is None:
            result.refused = "needs the operator's confirmation"
            return f"This mission moves the robot and needs the operator's confirmation: {plan}"
        if not confirm(steps, forever):
            result.refused = "not confirmed by the operator"
            return f"Mission not started: not confirmed by the operator. ({plan})"
    gateway.start()  # the robot's live state: each step's end is read from it
    try:
        result.mission_id = runner.start(
            steps,
            request,
            source="chat",
            forever=forever,
            replace=live["id"] if live is not None else None,
        )
    except MissionError as exc:
        result.refused = str(exc)
        return f"Mission not started: {exc}"
    started = f"mission {result.mission_id} started: {total} step{'s' * (total != 1)} — {plan}"
    if live is not None:
        started += f" (it replaced mission {live['id']})"
    return started


_ABOUT = re.compile(
    r"\bmission\b|\bhow far along\b|\bwhat (?:did|has) the robot (?:do|done)\b"
    r"|\bwhat (?:have|did) you (?:do|done)\b|\bwhich step\b|\bsteps? (?:done|left)\b",
    re.I,
)
_START = re.compile(r"^(?:start|run|begin|launch|do)\b", re.I)


def about_mission(request: str) -> bool:
    """A question about the mission ("how far along is the mission?"), not an order."""
    text = request.strip()
    return bool(_ABOUT.search(text)) and not _START.match(text)


def mission_answer(store: Store, robot: str) -> str | None:
    """The latest mission, from its stored steps only; None when there is none."""
    row = store.running_mission(robot) or store.latest_mission()
    if row is None:
        return None
    m = view.as_json(store, row["id"])
    return None if m is None else view.done_text(m)


async def without_model(agent: Any, request: str, intents: list[Intent], result, emit) -> bool:
    """A question about the mission (answered from its stored steps), or a plain request of
    several steps (started as a mission); False: neither, the turn plans as usual."""
    runner = agent.missions
    if runner is None:
        return False
    if about_mission(request):
        said = await asyncio.to_thread(mission_answer, agent.store, runner.robot)
        if said is not None:  # grounded in the stored steps, not in a model's words
            result.answer, result.grounding = said, "mission record"
            emit("answer_token", said)
            return True
    text, forever = mission_plan.until_stopped(request)
    if not (forever or mission_plan.may_be_mission(request, intents)):
        return False
    try:
        steps = await asyncio.to_thread(mission_plan.steps_for, text, agent.places())
    except mission_plan.TooManySteps as exc:  # said, never cut short into another plan
        result.refused = result.answer = f"I did not start this mission: {exc}."
        emit("answer_token", result.answer)
        return True
    if steps:
        await begin(agent, request, steps, result, emit)
    return bool(steps)


async def begin(agent: Any, request: str, steps: list[Step], result: TurnResult, emit) -> None:
    """The agent's mission started (or refused, and why), as the turn's answer."""
    confirm = confirmer(agent.confirm_mission, agent.confirm, agent._review)
    forever = mission_plan.until_stopped(request)[1]
    run = partial(start, forever=forever, replace=agent.replace_mission)
    result.answer = await asyncio.to_thread(
        run, agent.gateway, agent.missions, request, steps, agent._review, confirm, result
    )
    result.grounding = "mission"
    emit("answer_token", result.answer)
