"""Saving where the robot is under a name, on a robot with no save service of its own (a
TurtleBot3): astiop reads the robot's pose now, by its pose role, and keeps the place in its own
store; the answer says what was read, from which topic. Nothing is saved from a pose not read."""

from __future__ import annotations

import math
from typing import Any

from astiop.agent.intent import Intent
from astiop.agent.roles import pose_of
from astiop.robot.backend import Execution
from astiop.store.records import LocationError


def asked(intents: list[Intent], profile: Any) -> str | None:
    """The name to save the robot's pose under, when that is the whole request and the robot
    has no save service (else None: the robot's own service does it)."""
    if profile is None or profile.has("save_location") or len(intents) != 1:
        return None
    only = intents[0]
    return only.place if only.kind == "save" and only.place else None


def save_here(gateway: Any, store: Any, name: str) -> tuple[Execution | None, str]:
    """The read that was made (if any) and the answer."""
    pose_topic = gateway.profile.name("pose")
    if pose_topic is None:
        return None, "Not saved: this robot publishes no pose (`astiop robot profile`)."
    ex = gateway.run(f"ros2 topic echo {pose_topic} --once")
    pose = (
        pose_of(ex.values) if ex.executed and not ex.error and isinstance(ex.values, dict) else None
    )
    if pose is None:
        return ex, f"Not saved: the robot's pose could not be read ({ex.error or ex.reason})."
    x, y, theta = pose
    try:
        store.add_location(name, x, y, theta, "saved by the operator")
    except LocationError as exc:
        return ex, f"Not saved: {exc}"
    return ex, (
        f"Saved '{name}' at x {x:.2f} m, y {y:.2f} m, heading {math.degrees(theta):.0f} deg: "
        f"the robot's pose as it reported it on {pose_topic}."
    )
