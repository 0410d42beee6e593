"""Stage 2 on a robot of another make (`bench run --stage 2 --robot ros2` against a TurtleBot3
under Nav2): the cases are written in the ASTIbot's names, the paper's robot; each expected
command is carried over to the robot's own names by the role its name plays (the pose, the
battery, navigation, the stop ...), and a case that needs a role the robot has not, or a place
its map does not hold, is skipped with the reason: never scored against names the robot lacks.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from astiop.bench.suites import RobotCase
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.profile import match_profile
from astiop.ros2.validation import CANCEL_SUFFIX

Locate = Callable[[str], tuple[float, float] | None]

# what each answer and outcome check reads, by role
ANSWER_ROLES = {
    "battery": "battery",
    "position": "pose",
    "obstacles": "obstacles",
    "state": "status",
    "loaded": "conveyor",
    "healthy": "diagnostics",
}
OUTCOME_ROLES = {"arrive": "navigation", "docked": "dock", "loaded": "conveyor"}


@functools.cache
def _astibot_roles() -> dict[str, str]:
    """The ASTIbot's names -> the roles they play (the cases' names)."""
    profile = match_profile(astibot_catalog())
    return {m.name: role for role, m in profile.matches.items() if m.name}


def on_robot(case: RobotCase, profile: Any, locate: Locate) -> tuple[RobotCase, str]:
    """(the case in the robot's own names, "") or (the case, why it cannot run on it)."""
    if profile.make == "astibot" and not profile.namespace:
        return case, ""
    for key in case.answer:
        role = ANSWER_ROLES.get(key, key)
        if not profile.has(role):
            return case, f"its answer is checked against the robot's {role}: this robot has none"
    for key, want in case.outcome.items():
        role = OUTCOME_ROLES.get(key)
        if role and not profile.has(role):
            return case, f"its outcome ({key}) needs the robot's {role}: this robot has none"
        if key == "arrive" and isinstance(want, str) and locate(want) is None:
            return case, f"'{want}' is no place on this robot's map"
    start = case.setup.get("start", "docked")
    if isinstance(start, str) and start != "docked" and locate(start) is None:
        return case, f"its start '{start}' is no place on this robot's map"
    expect = []
    for expected in case.expect:
        alternatives = [carried(alt.split(), profile, locate) for alt in expected.split("|")]
        found = [a for a in alternatives if a]
        if not found:
            return case, f"nothing on this robot does `{expected.strip()}`"
        expect.append(" | ".join(found))
    return replace(case, expect=tuple(expect)), ""


def carried(words: list[str], profile: Any, locate: Locate) -> str | None:
    """One expectation ("verb sub /name key=value ...") in the robot's names, or None."""
    verb, sub, name, *args = words
    role = _astibot_roles().get(name)
    if role is None:
        return None
    if role == "navigation":
        return _navigation(args, profile, locate)
    if role == "stop" and not profile.has("stop"):
        if profile.kind("navigation") == "action":  # Nav2: its goals cancelled
            return f"service call {profile.name('navigation')}{CANCEL_SUFFIX}"
        velocity = profile.name("velocity_command")
        return f"topic pub {velocity} sign=0,0,0" if velocity else None
    target = profile.name(role)
    return " ".join([verb, sub, target, *args]) if target else None


def _navigation(args: list[str], profile: Any, locate: Locate) -> str | None:
    target, kind = profile.name("navigation"), profile.kind("navigation")
    if kind == "service":  # by name or coordinates, as the ASTIbot's /goto_position
        return " ".join(["service", "call", target, *args])
    if kind != "action":
        return None
    given = dict(a.split("=", 1) for a in args)
    xy = locate(given["name"]) if "name" in given else (float(given["x"]), float(given["y"]))
    return f"action send_goal {target} x={xy[0]:g} y={xy[1]:g}" if xy else None
