"""Serving a simulated robot as ROS 2 nodes: what it needs, where it serves, until a signal.
Importable without ROS 2 (the console checks with it before starting `astiop sim node`)."""

from __future__ import annotations

import os
import signal
from collections.abc import Callable
from typing import Any


class NodeSetupError(Exception):
    """What is missing, and the one thing to do about it."""


def check_imports() -> None:
    from astiop.transports.rclpy.available import rclpy_missing

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


def serve_until_signal(robot: Any, started: Callable[[], str], say: Callable[[str], None]) -> None:
    """Start `robot` (start/spin/stop/close), say `started()`, serve until SIGINT or SIGTERM —
    even when started with SIGINT ignored (a script's `&` job)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: robot.stop())
    robot.start()
    try:
        say(started())
        robot.spin()
    finally:
        robot.close()
