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
from astiop.ros2.fleet_names import namespaces


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


def discovered(catalog: Catalog) -> list[FleetRobot]:
    return [FleetRobot(name=ns.lstrip("/"), namespace=ns) for ns in namespaces(catalog)]


# A fleet found on the graph is looked for until no new robot appeared this long: DDS may
# discover one robot's participant seconds after another's (a loaded machine: over 2 s, for
# `fleet list` and `mcp` alike)
FOUND_ONCE_S = 5.0


def find_robots(
    settings: Settings,
    on_found: Callable[[FleetRobot], None] | None = None,
    settle_s: float | None = None,
) -> list[FleetRobot]:
    """The fleet's robots: the settings' list, or every robot namespace on the domain, read
    until the graph has shown no new robot for `settle_s` (FOUND_ONCE_S; or
    robot.ros2_timeout_s); `on_found(robot)` as each is found."""
    on_found = on_found or (lambda _robot: None)
    if settings.fleet.discover == "list":
        listed = listed_robots(settings)
        for robot in listed:
            on_found(robot)
        return listed
    finder = FleetFinder(settings)
    try:
        return finder.settle(on_found, settle_s or FOUND_ONCE_S)
    finally:
        finder.close()


def listed_robots(settings: Settings) -> list[FleetRobot]:
    if settings.robot.backend != "ros2":
        raise FleetError("a fleet is reached over ROS 2: add --robot ros2")
    if not settings.fleet.robots:
        raise FleetError(
            "no fleet: list its robots as [[fleet.robots]] in the settings, or --fleet auto"
        )
    return list(settings.fleet.robots)


class FleetFinder:
    """Every robot namespace on the domain, read off the graph (names only, no parameter) as
    often as `poll()` is called; the robots found so far in `found`."""

    def __init__(self, settings: Settings):
        from astiop.robot.factory import make_robot_gateway
        from astiop.transports.base import BackendError

        if settings.robot.backend != "ros2":
            raise FleetError("a fleet is reached over ROS 2: add --robot ros2")
        self.settings = settings
        whole = settings.model_copy(
            update={"robot": settings.robot.model_copy(update={"namespace": ""})}
        )
        try:
            self._gateway = make_robot_gateway(whole, None, who="fleet", discover=False)
        except BackendError as exc:
            raise FleetError(f"the ROS 2 graph could not be read: {exc}") from None
        self._gateway.backend.params_wanted = False  # namespaces are found from the names alone
        self.found: dict[str, FleetRobot] = {}

    def poll(self) -> list[FleetRobot]:
        """The robots found on the graph since the last poll."""
        self._gateway.backend.refresh(settle=False)  # polled: the graph as it is now
        new = [r for r in discovered(self._gateway.catalog) if r.name not in self.found]
        for robot in new:
            self.found[robot.name] = robot
        return new

    def settle(
        self, on_found: Callable[[FleetRobot], None], settle_s: float, wanted: str | None = None
    ) -> list[FleetRobot]:
        """Poll until the graph has shown no new robot for settle_s (one found at least, and
        the robot named `wanted`), or robot.ros2_timeout_s; every robot found, by name."""
        now = time.monotonic()
        deadline, changed = now + self.settings.robot.ros2_timeout_s, now

        def enough() -> bool:
            return bool(self.found) and (not wanted or wanted in self.found)

        while now < deadline and not (enough() and now - changed >= settle_s):
            for robot in self.poll():
                changed = time.monotonic()
                on_found(robot)
            time.sleep(0.1)
            now = time.monotonic()
        if not self.found:
            raise FleetError(
                "no robot namespace on the ROS 2 domain (a velocity command and a pose under one)"
            )
        return sorted(self.found.values(), key=lambda r: r.name)  # a stable order

    def close(self) -> None:
        self._gateway.close()
