"""`astiop sim node` in one call: check what it needs, say where it serves, serve until a signal."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

from astiop.sim_robots.serving import (
    NodeSetupError,
    check_imports,
    serve_until_signal,
    where,
)

__all__ = ["NodeSetupError", "check_imports", "serve"]


def serve(seed: int, speed: float, say: Callable[[str], None]) -> None:
    check_imports()
    from astiop.sim_robots.ros2_node.node import SimRobotNodes

    with tempfile.TemporaryDirectory(prefix="astiop-sim-node-") as folder:
        robot = SimRobotNodes(seed=seed, speed=speed, locations_db=Path(folder) / "robot.db")

        def started() -> str:
            nodes = ", ".join(robot.catalog.nodes[:-1])
            return f"ASTIbot simulator up as ROS 2 nodes ({nodes}) on {where()}; Ctrl-C stops it"

        serve_until_signal(robot, started, say)
