"""Every robot of a fleet served by one MCP server: each tool takes `robot` (its name; left out,
the only robot, else a refusal that lists them), and `fleet_status` lists every robot as it
last reported. One robot is a fleet of one."""

from __future__ import annotations

import inspect
import typing
from collections.abc import Callable

from astiop.mcp.tools import Refused, RobotTools
from astiop.robot.fleet_watch import row_of


class FleetTools:
    def __init__(self, robots: dict[str, RobotTools]):
        if not robots:
            raise ValueError("a fleet of no robots")
        self.robots = robots
        for name, tools in robots.items():
            tools.name = name

    @property
    def first(self) -> RobotTools:
        return next(iter(self.robots.values()))

    def pick(self, robot: str) -> RobotTools:
        """The robot a call names (the only one when it names none)."""
        names = ", ".join(self.robots)
        if not robot:
            if len(self.robots) == 1:
                return self.first
            raise Refused(f"this server reaches {len(self.robots)} robots: name one (robot: "
                          f"{names})")  # fmt: skip
        if robot not in self.robots:
            raise Refused(f"no robot named '{robot[:64]}' here (its robots: {names})")
        return self.robots[robot]

    def fleet_status(self) -> list[dict]:
        """Every robot: name, state, battery, pose, speed, goal, who controls it, as reported."""
        rows = []
        for name, tools in self.robots.items():
            gw = tools.gateway
            st = gw.state()
            row = row_of(name, gw.profile.namespace, gw).as_json()
            row["heard"] = st.lost_s is None
            if gw.lease is not None:
                holder = gw.lease.holder()
                row["control"] = "this server" if gw.lease.held else (
                    holder.words if holder else "free"
                )  # fmt: skip
            rows.append(row)
        return rows

    def tool(self, name: str) -> Callable:
        """Tool `name` of RobotTools with `robot` added to its parameters, for the SDK to read."""
        method = getattr(RobotTools, name)
        hints = typing.get_type_hints(method)
        params = [
            p.replace(annotation=hints.get(p.name, p.annotation))
            for p in list(inspect.signature(method).parameters.values())[1:]
        ]
        robot = inspect.Parameter("robot", inspect.Parameter.KEYWORD_ONLY, default="",
                                  annotation=str)  # fmt: skip

        def call(*args, robot: str = "", **kwargs):
            return getattr(self.pick(robot), name)(*args, **kwargs)

        call.__name__ = name
        call.__doc__ = method.__doc__
        call.__signature__ = inspect.Signature(
            [*params, robot], return_annotation=hints.get("return", inspect.Signature.empty)
        )
        return call
