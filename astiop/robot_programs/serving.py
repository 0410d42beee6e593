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


PROBE_S = 1.5  # a new participant hears the live ones on the loopback well within this


def robot_already_there(velocity_topics: list[str], wait_s: float = PROBE_S) -> str | None:
    """A robot already on this domain under these names (a base listening to one of the velocity
    topics), said in words; None: the names are free. A participant of its own, for a moment: a
    new participant learns of live peers only (a robot killed a moment ago is not one)."""
    import time

    import rclpy
    from rclpy.node import Node

    context = rclpy.Context()
    rclpy.init(args=["--ros-args", "--disable-stdout-logs"], context=context)
    try:
        node = Node(f"astiop_probe_{os.getpid()}", context=context)
        deadline = time.monotonic() + wait_s
        while True:
            for topic in velocity_topics:
                bases = [i.node_name for i in node.get_subscriptions_info_by_topic(topic)]
                if bases:
                    return f"{', '.join(sorted(set(bases)))} already listens to {topic}"
            if time.monotonic() > deadline:
                return None
            time.sleep(0.1)
    finally:
        rclpy.shutdown(context=context)


def refuse_a_taken_graph(velocity_topics: list[str], join: bool) -> None:
    """A simulator never speaks on a graph where a robot of the same names is (a real base):
    NodeSetupError, unless told to `join` it."""
    if join:
        return
    there = robot_already_there(velocity_topics)
    if there:
        raise NodeSetupError(
            f"a robot is already on {where()}: {there}; the simulator would speak to it "
            "(another ROS_DOMAIN_ID, or --join to share its names on purpose)"
        )


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
