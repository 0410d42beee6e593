"""What this turn's results support: every number, state word, place and quantity the robot
reported, and the commands astiop sent, gathered as `Facts` for grounding to hold an answer to."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from astiop.agent.roles import role_of
from astiop.agent.stated_numbers import NUMBER, quantities_in
from astiop.agent.summaries import (
    GOAL_ACCEPTED,
    GOAL_SENT,
    STATUS_WORDS,
    commanded_twist,
    directions,
    summarize,
)
from astiop.transports.base import Execution

GOAL = re.compile(r"\bgoals?\b", re.I)
_PLACE_IN_COMMAND = re.compile(r"name:\s*'?([\w-]+)")
_PLACE_IN_REPORT = re.compile(
    rf"(?:{GOAL_ACCEPTED}|{GOAL_SENT}|arrived|still going to|stopped short of):? ([\w-]+)"
)


@dataclass
class Facts:
    numbers: list[float] = field(default_factory=list)
    words: set[str] = field(default_factory=set)
    kinds: set[str] = field(default_factory=set)  # obstacle kinds reported
    measured: list[float] = field(
        default_factory=list
    )  # numbers the results hold (not the request's)
    places: set[str] = field(
        default_factory=set
    )  # named places in this turn's commands and reports
    text: str = ""  # everything the results and the commands say, lower case (for names)
    goal_said: bool = False  # a result or command (not the request) speaks of a goal
    quantities: list[tuple[float, str]] = field(default_factory=list)  # (value, unit) reported
    directions: set[str] | None = None  # the directions astiop commanded, when it published


def _walk(value: Any, key: str = "") -> Iterable[tuple[str, float]]:
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _walk(v, str(k))
    elif isinstance(value, list):
        for v in value[:400]:
            yield from _walk(v, key)
    elif isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        yield key, float(value)


def _strings(value: Any) -> Iterable[str]:
    if isinstance(value, dict):
        for v in value.values():
            yield from _strings(v)
    elif isinstance(value, list):
        for v in value[:100]:
            yield from _strings(v)
    elif isinstance(value, str) and len(value) <= 80:
        yield value.lower()


def facts_of(
    request: str,
    executions: list[Execution],
    outcome: str | None = None,
    reported: Iterable[str] = (),
) -> Facts:
    """What this turn's results support; `reported` is other text the robot reported (the
    started goal's distance to go, a waited goal's outcome)."""
    facts = Facts()
    facts.numbers += [float(n) for n in NUMBER.findall(request)]
    texts = [request, *reported]
    for line in reported:
        facts.quantities += quantities_in(line)
        numbers = [float(n) for n in NUMBER.findall(line)]
        facts.numbers += numbers
        facts.measured += numbers
        facts.words |= set(re.findall(r"[a-z_-]+", line.lower()))
        facts.places |= set(_PLACE_IN_REPORT.findall(line))
    for ex in executions:
        facts.numbers += [float(n) for n in NUMBER.findall(ex.command)]
        facts.places |= set(_PLACE_IN_COMMAND.findall(ex.command))
        texts += [ex.command, ex.reason, ex.error]
        if not ex.executed or ex.error:
            facts.words.add("error")
            continue
        summary = summarize(ex)
        texts += [ex.output, summary]
        facts.quantities += quantities_in(summary)
        if (twist := commanded_twist(ex)) is not None:
            facts.directions = (facts.directions or set()) | directions(twist)
        numbers = [float(n) for n in NUMBER.findall(summary)]
        facts.numbers += numbers
        facts.measured += numbers
        for text in _strings(ex.values):
            facts.words |= {text, *re.findall(r"[a-z_-]+", text)}
        for key, v in _walk(ex.values):
            extra = [v]
            if key in ("percentage",):
                extra.append(v * 100)
            if key in ("theta", "bearing", "angle_min", "angle_max", "yaw", "z", "w"):
                extra.append(math.degrees(v))
            facts.numbers += extra
            facts.measured += extra
        _words(ex, facts)
    facts.text = " ".join(t for t in texts if t).lower()
    # a job the robot accepted (a trip, a dock) is a goal, whether or not a result says so
    facts.goal_said = "accepted" in facts.words or any(GOAL.search(t) for t in texts[1:] if t)
    if outcome == "succeeded":
        facts.words |= {"arrived", "succeeded", "stopped"}
    elif outcome:
        facts.words.add(outcome)
    return facts


def _words(ex: Execution, facts: Facts) -> None:
    v = ex.values if isinstance(ex.values, dict) else {}
    cmd, role = ex.command, role_of(ex)
    if role == "status" and "state" in v:
        facts.words.add(str(v["state"]))
        if v.get("fault"):
            facts.words.add("fault")
        if float(v.get("speed", 0.0)) < 0.05:
            facts.words.add("stopped")
        else:
            facts.words.add("moving")
        facts.words.add("docked" if v.get("docked") else "undocked")
        if v.get("e_stopped"):
            facts.words.add("e_stopped")
    if role == "battery" and "percentage" in v:
        facts.words.add(STATUS_WORDS.get(v.get("power_supply_status"), "unknown"))
    if role == "conveyor" and "loaded" in v:
        facts.words.add("loaded" if v["loaded"] else "empty")
        facts.words.add("running" if v.get("running") else "stopped")
    if role == "obstacles" and "count" in v:
        facts.words.add("obstacles" if v["count"] else "clear")
        facts.kinds |= {str(o.get("kind", "")).lower() for o in v.get("obstacles", [])}
    if role == "diagnostics" and "status" in v:
        levels = [s.get("level", 0) for s in v["status"]]
        facts.words.add("healthy" if all(lv == 0 for lv in levels) else "fault")
    if role in ("odometry", "pose") and "twist" in v:
        t = v["twist"]["twist"]["linear"]
        facts.words.add("moving" if math.hypot(t["x"], t["y"]) >= 0.05 else "stopped")
    if "success" in v:
        if not v["success"]:
            facts.words.add("error")
        elif ex.provenance != "accepted":  # a goal accepted has not succeeded yet
            facts.words.add("succeeded")
        if v["success"] and "/goto_position" in cmd:
            facts.words |= {"accepted", "navigating", "moving"}
        if v["success"] and "/stop" in cmd:
            facts.words.add("stopped")
        if v["success"] and "/dock" in cmd:
            facts.words |= {"accepted", "docking", "moving"}
        if v["success"] and "/undock" in cmd:
            facts.words |= {"accepted", "undocking", "moving"}
        if v["success"] and "/conveyor/load" in cmd:
            facts.words |= {"accepted", "loading"}
        if v["success"] and "/conveyor/unload" in cmd:
            facts.words |= {"accepted", "unloading"}
    if v.get("accepted"):
        facts.words |= {"accepted", "navigating", "moving"}
