"""`astiop sim node` in one call: check what it needs, say where it serves, serve until a signal."""

from __future__ import annotations

import os
import signal
import tempfile
from collections.abc import Callable
from pathlib import Path


class NodeSetupError(Exception):
    """What is missing, and the one thing to do about it."""


def check_imports() -> None:
    from astiop.robot.backends.rclpy.available import rclpy_missing

    missing = rclpy_missing()  # the same packages the rclpy transport needs
    if missing:
        hint = (
            ""
            if "build-interfaces" in missing
            else (': pip install "astiop[ros]", or source your ROS 2 setup.bash')
        )
        raise NodeSetupError(f"ROS 2 is not ready here: {missing}{hint}")


def where() -> str:
    """The domain and discovery range this process will use, as the ROS environment sets them."""
    domain = os.environ.get("ROS_DOMAIN_ID", "0") or "0"
    scope = os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") or (
        "LOCALHOST" if os.environ.get("ROS_LOCALHOST_ONLY") == "1" else "SUBNET (the default)"
    )
    return f"ROS_DOMAIN_ID={domain}, discovery range {scope}"


def serve(seed: int, speed: float, say: Callable[[str], None]) -> None:
    check_imports()
    from astiop.sim_robots.ros2_node.node import SimRobotNodes

    with tempfile.TemporaryDirectory(prefix="astiop-sim-node-") as folder:
        robot = SimRobotNodes(seed=seed, speed=speed, locations_db=Path(folder) / "robot.db")
        # Stop on Ctrl-C or SIGTERM, even when started with SIGINT ignored (a script's `&` job)
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: robot.stop())
        robot.start()
        try:
            nodes = ", ".join(robot.catalog.nodes[:-1])
            say(f"ASTIbot simulator up as ROS 2 nodes ({nodes}) on {where()}; Ctrl-C stops it")
            robot.spin()
        finally:
            robot.close()
