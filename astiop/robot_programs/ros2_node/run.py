"""`astiop sim node` in one call: check what it needs, say where it serves, serve until a signal."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

from astiop.robot_programs.serving import (
    NodeSetupError,
    check_imports,
    refuse_a_taken_graph,
    serve_until_signal,
    where,
)

__all__ = ["NodeSetupError", "check_imports", "serve", "serve_fleet"]


def serve(seed: int, speed: float, say: Callable[[str], None], join: bool = False) -> None:
    check_imports()
    refuse_a_taken_graph(["/cmd_vel"], join)
    from astiop.robot_programs.ros2_node.node import SimRobotNodes

    with tempfile.TemporaryDirectory(prefix="astiop-sim-node-") as folder:
        robot = SimRobotNodes(seed=seed, speed=speed, locations_db=Path(folder) / "robot.db")

        def started() -> str:
            nodes = ", ".join(robot.catalog.nodes[:-1])
            return f"ASTIbot simulator up as ROS 2 nodes ({nodes}) on {where()}; Ctrl-C stops it"

        serve_until_signal(robot, started, say)


def serve_fleet(
    names: list[str], *, seed: int, speed: float, domains: list[int] | None, say, join=False
) -> None:
    """N ASTIbots in one warehouse, each under /NAME on this domain, or on domains[i]."""
    check_imports()
    if not domains:  # (each robot on a domain of its own: their own domains, not this one)
        refuse_a_taken_graph([f"/{n}/cmd_vel" for n in names], join)
    from astiop.robot_programs.ros2_node.fleet import SimFleetNodes

    with tempfile.TemporaryDirectory(prefix="astiop-sim-fleet-") as folder:
        fleet = SimFleetNodes(names, seed=seed, speed=speed, folder=Path(folder), domains=domains)

        def started() -> str:
            if domains:
                placed = ", ".join(f"{n} on ROS_DOMAIN_ID={d}" for n, d in zip(names, domains))
                scope = where().split(", ", 1)[1]
                return (
                    f"{len(names)} ASTIbots up as ROS 2 nodes: {placed}; {scope}; Ctrl-C stops them"
                )
            spaces = f"/{names[0]}" if len(names) == 1 else f"/{names[0]} … /{names[-1]}"
            return (
                f"{len(names)} ASTIbot{'s' if len(names) > 1 else ''} up as ROS 2 nodes under "
                f"{spaces} in one warehouse on {where()}; Ctrl-C stops them"
            )

        serve_until_signal(fleet, started, say)
