"""A goal a turn started: what the robot reported when it accepted it (or that it was sent, on a
goal topic, which answers nothing), and how it ended.

A turn never waits for its last goal; it says what was started, and the follow-up says how it
ended (arrived, aborted, canceled, e-stopped) when it does.
"""

from __future__ import annotations

import asyncio
import math
import re
import time

from astiop.agent.summaries import GOAL_ACCEPTED as ACCEPTED
from astiop.agent.summaries import GOAL_SENT as SENT
from astiop.robot.gateway import RobotGateway
from astiop.ros2.render import POSE_STAMPED
from astiop.transports.base import Execution
from astiop.transports.state import LOST

NAVIGATING = ("/goto_position", "/dock", "/undock", "send_goal", POSE_STAMPED)
MOVING = ("navigating", "docking", "undocking", "blocked")
ARRIVED_M = 0.3
STATUS_LAG_S = 2.0  # a status stream may still say idle this long after a goal starts
NO_STATUS_S = 15.0  # a robot that reports no status at all: the pose decides after this


def started(ex: Execution) -> bool:
    """Whether the command started a goal the robot is now driving to."""
    if not ex.executed or ex.error or not any(k in ex.command for k in NAVIGATING):
        return False
    if started_word(ex) == SENT:  # a goal published on a navigator's /goal_pose
        return True
    v = ex.values if isinstance(ex.values, dict) else {}
    return bool(v.get("success") or v.get("accepted"))


def goal_name(ex: Execution) -> str:
    m = re.search(r"name:\s*'?([\w-]+)", ex.command)
    if m:
        return m.group(1)
    if "/undock" in ex.command:
        return "undock"
    if "/dock" in ex.command:
        return "dock"
    xy = re.search(r"x:\s*(-?[\d.]+).*?y:\s*(-?[\d.]+)", ex.command)
    return f"({float(xy[1]):g}, {float(xy[2]):g})" if xy else "the goal"


def target_of(ex: Execution, places: dict[str, tuple[float, float]]) -> tuple[float, float] | None:
    """Where the goal is, when the command says: a named place's x, y or the coordinates."""
    name = goal_name(ex)
    if name in places:
        return places[name]
    xy = re.search(r"x:\s*(-?[\d.]+).*?y:\s*(-?[\d.]+)", ex.command)
    return (float(xy[1]), float(xy[2])) if xy else None


def outcome_at(gateway: RobotGateway, target: tuple[float, float] | None, name: str = "") -> str:
    """How a goal that reported no outcome ended, from the robot's reported state and pose
    (for a dock or undock, from its reported docked flag)."""
    state = gateway.state()
    if state.state_word in MOVING:
        return "still going"
    if name in ("dock", "undock") and state.status is not None:
        return "succeeded" if state.status.docked == (name == "dock") else "stopped short"
    if target is not None and state.pose is not None:
        if math.dist((state.pose.x, state.pose.y), target) <= ARRIVED_M:
            return "succeeded"
        return "stopped short"
    return "ended"


def started_text(gateway: RobotGateway, ex: Execution) -> str:
    """'goal accepted: shipping, 11.4 m to go' ('goal sent: …' on a goal topic), the distance
    along the robot's own /plan."""
    deadline = time.monotonic() + 1.0
    while True:
        togo = gateway.state().distance_remaining
        if togo is not None or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    text = f"{started_word(ex)}: {goal_name(ex)}"
    return text + (f", {togo:.1f} m to go" if togo is not None else "")


def started_word(ex: Execution) -> str:
    """'goal accepted' as the robot said it; 'goal sent' for one published on a goal topic,
    which tells nothing of acceptance."""
    return SENT if POSE_STAMPED in ex.command else ACCEPTED


async def follow(
    gateway: RobotGateway,
    started_line: str,
    timeout_s: float,
    target: tuple[float, float] | None = None,
) -> tuple[str, str]:
    """Wait for the goal to end: (outcome, a line for the operator).

    A robot that reports no outcome (a service goal ends as an idle status) arrived when its
    reported pose is within ARRIVED_M of the target. Waits in steps of a second, so a canceled
    follow-up leaves no thread behind for long."""
    t0 = time.monotonic()
    deadline = t0 + timeout_s
    outcome, timed_out = None, False
    while outcome is None:
        step = max(0.0, min(1.0, deadline - time.monotonic()))
        outcome = await asyncio.to_thread(gateway.wait_until_idle, step)
        if outcome is None and time.monotonic() >= deadline:
            timed_out = True
            break
        state = await asyncio.to_thread(gateway.state)
        if state.lost_s is not None:
            outcome = LOST  # not aborted, never succeeded: its end was not heard
        elif state.e_stopped:
            outcome = "e-stopped"
        idle = not (state.status and state.status.active_goal)
        # a status not yet received is not "idle": a CLI stream may take seconds to start
        waited = time.monotonic() - t0
        settled = waited > STATUS_LAG_S and (state.status is not None or waited > NO_STATUS_S)
        if outcome is None and idle and state.state_word not in MOVING and settled:
            break
    if timed_out:
        outcome = "still going"
    where = re.sub(rf"^(?:{ACCEPTED}|{SENT}): |, [\d.]+ m to go$", "", started_line)
    if outcome is None:
        outcome = await asyncio.to_thread(outcome_at, gateway, target, where)
    state = await asyncio.to_thread(gateway.state)
    if outcome == "succeeded":
        text = {"dock": "docked", "undock": "undocked"}.get(where, f"arrived: {where}")
        if state.pose is not None:
            text += f" (x {state.pose.x:.2f}, y {state.pose.y:.2f})"
    elif outcome == "still going":
        text = f"still going to {where}"
    elif outcome == LOST:
        text = f"lost contact with the robot during the goal to {where}"
    elif outcome == "stopped short" and where in ("dock", "undock"):
        text = f"not {where}ed: the robot reports docked {state.status and state.status.docked}"
    elif outcome == "stopped short" and target is not None and state.pose is not None:
        off = math.dist((state.pose.x, state.pose.y), target)
        text = f"stopped short of {where}: {off:.1f} m from it"
    elif outcome == "ended":
        text = f"the goal to {where} ended; the robot did not report how"
    else:
        text = f"goal {outcome}: {where}"
    return outcome, text
