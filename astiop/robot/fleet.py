"""A fleet: several robots on one ROS 2 domain, each under its own namespace (the ROS 2
convention: /tb3_1/cmd_vel, /tb3_2/cmd_vel). Its robots are the settings' [[fleet.robots]], or
with fleet.discover = "auto" every namespace on the graph that holds a velocity command and a
pose or odometry, each named for its namespace (/tb3_2 is tb3_2). A robot is addressed by its
name (--robot-name): the settings of that one robot are the fleet's, its namespace and profile
put in robot.namespace and robot.profile."""

from __future__ import annotations

import time
from collections.abc import Callable

from astiop.config import FleetRobot, Settings
from astiop.ros2.catalog import Catalog
from astiop.ros2.profile import ProfileSpec, match_profile


class FleetError(ValueError):
    """A robot name or fleet that cannot be used, said in one line."""


def is_fleet(settings: Settings) -> bool:
    return settings.fleet.discover == "auto" or bool(settings.fleet.robots)


def robot_settings(settings: Settings, name: str) -> Settings:
    """The settings of the fleet's robot `name`."""
    found = next((r for r in settings.fleet.robots if r.name == name), None)
    if found is None and settings.fleet.discover == "auto":
        try:
            found = FleetRobot(name=name, namespace="/" + name)
        except ValueError:  # pydantic's ValidationError
            raise FleetError(
                f"'{name}' is no robot name: 1-64 letters, digits, '_' or '-'"
            ) from None
    if found is None:
        known = ", ".join(r.name for r in settings.fleet.robots) or "none"
        raise FleetError(
            f"no robot named '{name}' in the fleet (its robots: {known}; "
            "[[fleet.robots]] in the settings, or --fleet auto)"
        )
    robot = settings.robot.model_copy(
        update={"namespace": found.namespace, "profile": found.profile or settings.robot.profile}
    )
    return settings.model_copy(update={"robot": robot})


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


def discovered(catalog: Catalog) -> list[FleetRobot]:
    return [FleetRobot(name=ns.lstrip("/"), namespace=ns) for ns in namespaces(catalog)]


def find_robots(
    settings: Settings, on_found: Callable[[FleetRobot], None] | None = None
) -> list[FleetRobot]:
    """The fleet's robots: the settings' list, or every robot namespace on the domain, read
    until the graph has settled (or robot.ros2_timeout_s); `on_found(robot)` as each is found."""
    from astiop.robot.backend import BackendError
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.gateway import SETTLED_S

    on_found = on_found or (lambda _robot: None)
    if settings.robot.backend != "ros2":
        raise FleetError("a fleet is reached over ROS 2: add --robot ros2")
    if settings.fleet.discover == "list":
        if not settings.fleet.robots:
            raise FleetError(
                "no fleet: list its robots as [[fleet.robots]] in the settings, or --fleet auto"
            )
        for robot in settings.fleet.robots:
            on_found(robot)
        return list(settings.fleet.robots)
    whole = settings.model_copy(
        update={"robot": settings.robot.model_copy(update={"namespace": ""})}
    )
    try:
        gateway = make_robot_gateway(whole, None, who="fleet", discover=False)
    except BackendError as exc:
        raise FleetError(f"the ROS 2 graph could not be read: {exc}") from None
    gateway.backend.params_wanted = False  # namespaces are found from the names alone
    found: dict[str, FleetRobot] = {}
    try:
        now = time.monotonic()
        deadline, changed = now + settings.robot.ros2_timeout_s, now
        while now < deadline and not (found and now - changed >= SETTLED_S):
            gateway.backend.refresh()
            for robot in discovered(gateway.catalog):
                if robot.name not in found:
                    found[robot.name], changed = robot, time.monotonic()
                    on_found(robot)
            time.sleep(0.2)
            now = time.monotonic()
    finally:
        gateway.close()
    if not found:
        raise FleetError(
            "no robot namespace on the ROS 2 domain (a velocity command and a pose under one)"
        )
    return sorted(found.values(), key=lambda r: r.name)  # as found, and said, in a stable order
