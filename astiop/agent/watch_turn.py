"""A request that is a watch ("tell me when the battery is below 20 %"): read into a typed
watch, checked against the robot's roles, stored, and said back in one sentence; a watch that
cannot be kept is one line and nothing is stored. Any other request is planned as before.

A reaction that moves the robot ("..., then send it to the dock") is read as mission steps,
each checked now as the command it will send, and armed only once the operator approves it."""

from __future__ import annotations

import getpass
import socket
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

from astiop.agent import intent
from astiop.agent.intent import resolve_place
from astiop.missions.steps import Step, describe
from astiop.robot.safety import Review
from astiop.watches.model import Watch, WatchError, battery_percent, validate
from astiop.watches.reactions import ReactionError, mission_reaction
from astiop.watches.words import asks_to_be_told, split_reaction, watch_from_words

# (the question: the condition and every step) -> approved
ConfirmReaction = Callable[[str], bool]
_WHERE = {"console": "the console's Chat", "cli": "astiop chat"}


def steps_from_words(
    words: str,
    places: Mapping[str, tuple[float, float]],
    profile: Any = None,
    review: Callable[[str], Review] | None = None,
) -> list[Step]:
    """The mission steps a reaction's words name ("send it to the dock", "go to shipping and
    then dock"), read as the Chat reads a request; each step's command is built for `profile`
    and, with `review`, validated and checked by safety now. WatchError: one line."""
    steps: list[Step] = []
    for said in intent.classify(words, list(places)):
        if said.kind == "navigate" and (said.place or said.xy):
            xy = None if said.place else said.xy
            steps.append(Step("goto", place=said.place, xy=xy, theta=said.theta))
        elif said.kind in ("dock", "undock"):
            steps.append(Step(said.kind))
        elif said.kind == "navigate":
            known = ", ".join(sorted(places)) or "none on this map"
            raise WatchError(f"no place named in '{said.clause}' (the places: {known})")
        else:
            raise WatchError(f"a reaction docks, undocks or goes to a place, not '{said.clause}'")
    if not steps:
        raise WatchError(f"no reaction in '{words}': dock, undock or go to a place")
    return checked_steps(steps, places, profile, review)


def checked_steps(
    steps: list[Step],
    places: Mapping[str, tuple[float, float]],
    profile: Any = None,
    review: Callable[[str], Review] | None = None,
) -> list[Step]:
    """`steps`, each one's command built now for `profile` (a place unknown, a step the robot
    cannot take: WatchError) and, with `review`, validated and checked by safety."""
    for step in steps:
        if step.place and step.place not in places:
            known = ", ".join(sorted(places)) or "none on this map"
            raise WatchError(f"no place called '{step.place}' (the places: {known})")
        command = step.command(profile, places.get)
        if command is None:
            raise WatchError(f"this robot cannot {step.label()}")
        checked = review(command) if review is not None else None
        if checked is not None and not (checked.checked.valid and checked.allowed):
            raise WatchError(f"{step.label()}: {checked.reason or checked.checked.reason}")
    return steps


def question(watch: Watch, steps: list[Step]) -> str:
    """What the operator is asked before a reaction is armed."""
    return f"When {watch.condition()}, the robot will: {describe(steps)} (once). Arm it?"


def approver(where: str) -> str:
    """Who approved a reaction, as its mission keeps it: "ana on jetson (astiop watch add)"."""
    return f"{getpass.getuser()} on {socket.gethostname()} ({where})"


def armed(watch: Watch, steps: list[Step], approved_by: str) -> Watch:
    """The watch with its reaction, as the watches table keeps it (WatchError: one line)."""
    try:
        return validate(replace(watch, reaction=mission_reaction(steps, approved_by)))
    except ReactionError as exc:
        raise WatchError(str(exc)) from None


def kept(request: str, agent: Any) -> str | None:
    """The answer when the request is a watch (kept or not), else None."""
    condition, then = split_reaction(request)
    if not asks_to_be_told(condition):
        return None  # planned as before, the robot not read here
    profile = agent.gateway.profile
    try:
        places = agent.places()  # the store's places of the robot's map
        battery = battery_percent(agent.gateway.state())  # "reaches 20 %": down or up from here
        watch = watch_from_words(
            condition, agent.robot, places, lambda said: resolve_place(said, list(places)),
            (agent.robot,) if agent.robot else (),
            battery,
        )  # fmt: skip
        if watch is None:  # not a watch; one with a reaction is never planned to run now
            what = "no condition I can watch (a reading, a place reached, no progress)"
            return f"Not watched: {what} in '{condition}'; nothing was stored." if then else None
        watch = replace(validate(watch, profile), said=request.strip()[:300])
        steps = steps_from_words(then, places, profile, agent.gateway.review) if then else []
        if steps:
            armed(watch, steps, "-")  # it can be kept (once, at most 10 steps) before it is asked
    except WatchError as exc:
        return f"Not watched: {exc}; nothing was stored."
    if agent.store is None:
        shown = armed(watch, steps, "-").sentence() if steps else watch.sentence()
        return (  # the watch understood all the same (the bench's turns have no database)
            "Not watched: watches are kept in astiop's database, and there is none here; "
            f"it would be: I will tell you when {shown}."
        )
    approved = ""
    if steps:
        ask: ConfirmReaction | None = agent.confirm_reaction
        if ask is None:
            return (
                "Not watched: a reaction that moves the robot is approved by the operator, and "
                "no one can be asked here (astiop watch add '...' --then); nothing was stored."
            )
        if not ask(question(watch, steps)):
            return "Not watched: the reaction was not approved; nothing was stored."
        approved = approver(_WHERE.get(agent.recorder.session, "chat"))
        watch = armed(watch, steps, approved)
    watch_id = agent.store.add_watch(**watch.row())
    said = f"Watch {watch_id}: I will tell you when {watch.sentence()}."
    return f"{said} Armed, approved by {approved}." if approved else said
