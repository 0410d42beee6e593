"""What both live ROS 2 transports (rclpy, the `ros2` CLI) do alike with the robot's reported
state: which states move it, the plan of a finished goal dropped, and the wait for a goal's end."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from astiop.transports.state import LOST

MOVING = frozenset({"navigating", "docking", "undocking", "blocked"})


def without_finished_plan(messages: dict[str, dict[str, Any]], profile: Any) -> dict:
    """The state's messages, less the last plan of a goal that has ended (on a robot that
    reports its state; Nav2 publishes a plan only while it plans)."""
    status_name, plan = (profile.name("status"), profile.name("plan")) if profile else ("", "")
    if status_name and plan and (messages.get(status_name) or {}).get("state") not in MOVING:
        messages.pop(plan, None)
    return messages


def wait_until_idle(
    timeout_s: float,
    *,
    lost: Callable[[], bool],
    goals_running: Callable[[], bool],
    state: Callable[[], str | None],
    outcome: Callable[[], str | None],
) -> str | None:
    """Until no goal of this process runs and the robot reports no motion: how the goal ended
    (`outcome()`), LOST once the robot is not heard, None after `timeout_s`."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if lost():
            return LOST  # its goal's end will not be heard
        if not goals_running() and state() not in MOVING:
            return outcome()
        time.sleep(0.1)
    return None
