"""Every robot of a fleet served by one MCP server: each tool takes `robot` (its name; left out,
the only robot, else a refusal that lists them), and `fleet_status` lists every robot as it
last reported. One robot is a fleet of one. A fleet found on the graph keeps growing: a robot
that joins later is served from when it is found (`keep_adding`)."""

from __future__ import annotations

import contextlib
import inspect
import threading
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

    def add(self, name: str, tools: RobotTools) -> None:
        """A robot found after the start, served from now. The robots are replaced, not changed:
        a call meanwhile reads them as they were."""
        tools.name = name
        self.robots = {**self.robots, name: tools}

    def keep_adding(
        self,
        found: Callable[[], list[str]],
        tools_of: Callable[[str], RobotTools],
        every_s: float,
        halt: threading.Event,
    ) -> threading.Thread:
        """Every `every_s` until `halt`, each robot `found()` newly is served (`tools_of(name)`
        makes its tools, started; a robot it fails for is looked for again). On a thread."""

        def run() -> None:
            while not halt.wait(every_s):
                try:
                    names = found()
                except Exception:  # noqa: BLE001 - a graph not read this time: next time
                    continue
                for name in names:
                    if name not in self.robots and not halt.is_set():
                        with contextlib.suppress(Exception):  # tools_of says why, and forgets it
                            self.add(name, tools_of(name))

        thread = threading.Thread(target=run, name="mcp-fleet-find", daemon=True)
        thread.start()
        return thread

    @property
    def first(self) -> RobotTools:
        return next(iter(self.robots.values()))

    def pick(self, robot: str) -> RobotTools:
        """The robot a call names (the only one when it names none)."""
        robots = self.robots  # one reading: a robot may join meanwhile
        names = ", ".join(robots)
        if not robot:
            if len(robots) == 1:
                return next(iter(robots.values()))
            raise Refused(f"this server reaches {len(robots)} robots: name one (robot: "
                          f"{names})")  # fmt: skip
        if robot not in robots:
            raise Refused(f"no robot named '{robot[:64]}' here (its robots: {names})")
        return robots[robot]

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
        call.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
            [*params, robot], return_annotation=hints.get("return", inspect.Signature.empty)
        )
        return call
