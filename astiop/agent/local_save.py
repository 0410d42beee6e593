"""Named places on a robot with no place services of its own (a TurtleBot3): "save this spot"
reads the robot's pose now, by its pose role, and keeps the place in astiop's store under the
robot's map (the answer says what was read, from which topic; nothing is saved from a pose not
read); a place that map does not hold is said so, never guessed."""

from __future__ import annotations

import math
import re
from typing import Any

from astiop.agent.intent import Intent
from astiop.agent.roles import pose_of
from astiop.store.records import LocationError
from astiop.transports.base import Execution


def asked(intents: list[Intent], profile: Any) -> str | None:
    """The name to save the robot's pose under, when that is the whole request and the robot
    has no save service (else None: the robot's own service does it)."""
    if profile is None or profile.has("save_location") or len(intents) != 1:
        return None
    only = intents[0]
    return only.place if only.kind == "save" and only.place else None


_PLACE = re.compile(r"\b(?:to|at)\s+(?:the\s+)?([a-z][a-z0-9 _-]{1,40}?)[\s?.!]*$", re.I)


def unknown_place(request: str, intents: list[Intent], profile: Any, store: Any) -> str | None:
    """The answer to "go to X" when X is no place on the robot's map and the robot cannot look
    names up itself (no by-name navigation service): None otherwise."""
    if profile is None or store is None or profile.kind("navigation") == "service":
        return None
    if len(intents) != 1 or intents[0].kind != "navigate" or intents[0].place or intents[0].xy:
        return None
    m = _PLACE.search(request.strip())
    if m is None:
        return None
    known = ", ".join(loc.name for loc in store.list_locations()) or "none yet"
    others = ", ".join(sorted(store.other_maps()))
    elsewhere = f" (other maps hold places too: {others})" if others else ""
    return (
        f"There is no place named '{m.group(1).strip()}' on this robot's map "
        f"({store.map_name}); its places: {known}{elsewhere}. Say 'save this spot as NAME' "
        "where the robot stands, or give coordinates (go to x 1.0 y 0.5)."
    )


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
