"""The agent speaks of roles; the robot's profile supplies the names. The intent reader and the
tools name a reading by the ASTIbot's topic (its key here); on another robot the profile's name
for the same role is read instead, and a robot without the role says so: it is never offered a
substitute reading as if it were the one asked for."""

from __future__ import annotations

import math
from typing import Any

from astiop.ros2.roles import KEY_ROLES, READ_ROLES
from astiop.transports.base import Execution
from astiop.transports.state import battery_fraction, yaw_of

# each from the role's one definition (astiop.ros2.roles): the reader's key for a reading -> its
# role; what an answer calls a role; the role whose reading answers for another the robot lacks
WHAT = {r.name: r.label for r in READ_ROLES}
STANDS_IN = {r.name: r.stands_in for r in READ_ROLES if r.stands_in}


def name_for(key: str, profile: Any) -> str | None:
    """The robot's name for the reading the reader calls `key`; None when it has none."""
    role = KEY_ROLES.get(key)
    if role is None or profile is None:
        return key
    return profile.name(role) or (profile.name(STANDS_IN[role]) if role in STANDS_IN else None)


def lacking(keys: list[str], profile: Any) -> list[str]:
    """The roles among `keys` the robot has no name for."""
    return [KEY_ROLES[k] for k in keys if k in KEY_ROLES and name_for(k, profile) is None]


def nothing_to_read(intents: list, profile: Any) -> str | None:
    """When every clause asks only for readings the robot does not publish: the plain answer
    that it has none (no model, no substitute reading); else None."""
    if not intents or any(i.kind != "read" or not i.topic for i in intents):
        return None
    missing = lacking([i.topic for i in intents], profile)
    return none_sentence(missing) if len(missing) == len(intents) else None


def none_sentence(roles: list[str]) -> str:
    what = " or ".join(WHAT.get(r, r) for r in roles)
    return (
        f"This robot publishes no {what}: nothing on its graph plays that role "
        "(`astiop robot profile` lists what it has)."
    )


def role_of(ex: Execution) -> str:
    """The role of what a command read: as the gateway named it, else by the ASTIbot's name."""
    if ex.role:
        return ex.role
    parts = ex.command.split()
    return next((KEY_ROLES[p] for p in parts if p in KEY_ROLES), "")


def pose_of(v: dict) -> tuple[float, float, float] | None:
    """x, y, heading of a Pose2D, a PoseWithCovarianceStamped or an Odometry."""
    if "x" in v and "y" in v:
        return float(v["x"]), float(v["y"]), float(v.get("theta", 0.0))
    pose = v.get("pose", {}).get("pose", {}) if isinstance(v.get("pose"), dict) else {}
    pos = pose.get("position")
    if not isinstance(pos, dict):
        return None
    return float(pos.get("x", 0.0)), float(pos.get("y", 0.0)), yaw_of(pose.get("orientation", {}))


def battery_percent(ex: Execution) -> float:
    """The battery's charge in %, in the units the robot's profile says it reports."""
    return battery_fraction(ex.values.get("percentage"), ex.units) * 100.0


def no_return(r: Any, v: dict) -> bool:
    """A beam that hit nothing: sensor_msgs/LaserScan discards values outside [range_min,
    range_max] (a lidar's 0.0 is no return, not an obstacle at 0 m)."""
    if not isinstance(r, int | float) or not math.isfinite(r) or r <= 0.0:
        return True
    lo, hi = v.get("range_min", 0.0), v.get("range_max", math.inf)
    return r < lo or r > hi
