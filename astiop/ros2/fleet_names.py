"""Robots on one graph by namespace (the ROS 2 convention: /tb3_1/cmd_vel, /tb3_2/cmd_vel): which
namespaces hold a robot, and which robot a name is under."""

from __future__ import annotations

from astiop.ros2.catalog import Catalog
from astiop.ros2.profile import match_profile
from astiop.ros2.profile_types import ProfileSpec


def namespaces(catalog: Catalog) -> list[str]:
    """The namespaces on the graph that hold a robot: a velocity command and a pose or odometry
    matched inside it (a name's first segment is a candidate namespace)."""
    names = list(catalog.topics)
    candidates = sorted({"/" + n.split("/")[1] for n in names if n.count("/") >= 2})
    robots = []
    for ns in candidates:
        profile = match_profile(catalog, ProfileSpec(namespace=ns))
        if profile.has("velocity_command") and (profile.has("pose") or profile.has("odometry")):
            robots.append(ns)
    return robots


def robot_under(name: str | None, own: str, catalog: Catalog) -> str:
    """The namespace of another robot of the graph that `name` is under ("" : none, or `own`,
    the namespace of the robot a gateway or request is about). A namespace that holds a
    velocity command is a robot's, its pose not discovered yet or not."""
    if not name or name.count("/") < 2 or (own and name.startswith(own.rstrip("/") + "/")):
        return ""
    ns = "/" + name.split("/")[1]
    if ns == own:
        return ""
    drives = match_profile(catalog, ProfileSpec(namespace=ns)).has("velocity_command")
    return ns if drives else ""
