"""How one step ended, as the robot reported it: a goal followed to its end (its reported outcome,
checked against the pose or the docked flag), a service's reply, a reading."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

from astiop.missions.steps import Step, read_name
from astiop.robot.gateway import RobotGateway
from astiop.transports.base import Execution
from astiop.transports.state import LOST, battery_fraction

MOVING = ("navigating", "docking", "undocking", "blocked")
ARRIVED_M = 0.3
YES = lambda _c: True  # noqa: E731  (the operator approved the mission, and asks its cancel)
STATUS_LAG_S = 2.0  # a status stream may still say idle this long after a goal starts
NO_STATUS_S = 15.0  # a robot that reports no status at all: the pose decides after this


@dataclass
class StepEnd:
    status: str  # succeeded | skipped | failed | replaced | canceled | e-stopped | lost
    detail: str
    sent: bool = True  # False: refused before anything reached the robot


@dataclass(frozen=True)
class StepReport:
    mission_id: int
    seq: int
    total: int
    label: str
    status: str
    detail: str
    round: int | None = None  # a mission repeated until stopped: which round

    def line(self) -> str:
        mark = {"succeeded": "✓", "skipped": "–"}.get(self.status, "✗")
        where = f"round {self.round} step" if self.round else "step"
        return (
            f"{mark} {where} {self.seq + 1}/{self.total} {self.label}: {self.status} — "
            f"{self.detail}"
        )


def as_replaced(end: StepEnd, by: int) -> StepEnd:
    """The step a replacing mission cut short: 'replaced by mission M', never 'canceled'."""
    said = end.detail.replace("canceled by the operator", f"replaced by mission {by}", 1)
    return StepEnd("replaced", said)


def accepted(ex: Execution) -> bool:
    v = ex.values if isinstance(ex.values, dict) else {}
    return ex.executed and not ex.error and bool(v.get("success") or v.get("accepted"))


def refusal(ex: Execution) -> str:
    """Why the robot or the gateway did not take a command, in one line."""
    if ex.error:
        return ex.error
    if ex.reason and not ex.executed:
        return ex.reason
    v = ex.values if isinstance(ex.values, dict) else {}
    return str(v.get("message") or "the robot refused it")


def reading(what: str, ex: Execution) -> float | None:
    """battery in %, obstacles as a count, from an echo's message."""
    v = ex.values if isinstance(ex.values, dict) else None
    if not ex.executed or ex.error or v is None:
        return None
    if what == "battery" and isinstance(v.get("percentage"), (int, float)):
        return round(battery_fraction(v["percentage"], ex.units) * 100.0, 1)
    if what == "obstacles":
        if isinstance(v.get("count"), int):
            return float(v["count"])
        if isinstance(v.get("obstacles"), list):
            return float(len(v["obstacles"]))
    return None


def reading_text(what: str, value: float) -> str:
    return f"battery {value:.1f} %" if what == "battery" else f"{value:g} obstacle(s) seen"


def read(gateway: RobotGateway, what: str) -> tuple[float | None, str]:
    ex = gateway.run(f"ros2 topic echo {read_name(what, gateway.profile)} --once", source="mission")
    value = reading(what, ex)
    if value is None:
        return None, f"no {what} reading: {refusal(ex)}"
    return value, reading_text(what, value)


def follow_goal(
    gateway: RobotGateway,
    step: Step,
    target: tuple[float, float] | None,
    cancel: threading.Event,
    timeout_s: float,
) -> StepEnd:
    """Wait until the goal the step started ends, and say how, from what the robot reported."""
    t0 = time.monotonic()
    outcome: str | None = None
    # the goal the robot reports now, just after it took ours: another one later replaced it
    first = gateway.state().status
    ours = first.active_goal if first else ""
    while True:
        if cancel.is_set():
            return _cancel_goal(gateway, step)
        if time.monotonic() - t0 > timeout_s:
            return StepEnd("failed", f"did not end within {timeout_s:g} s")
        outcome = gateway.wait_until_idle(0.5)
        state = gateway.state()
        if state.e_stopped or outcome == "e-stopped":
            return StepEnd("e-stopped", "the E-STOP stopped the robot")
        if state.lost_s is not None or outcome == LOST:
            return StepEnd("lost", "lost contact with the robot: its end was not heard")
        goal = state.status.active_goal if state.status else ""
        ours = ours or goal
        if goal and goal != ours:
            return StepEnd("replaced", f"replaced by another goal ({goal}) before it ended")
        if outcome is not None:
            break
        idle = not (state.status and state.status.active_goal)
        waited = time.monotonic() - t0
        settled = waited > STATUS_LAG_S and (state.status is not None or waited > NO_STATUS_S)
        if idle and state.state_word not in MOVING and settled:
            break
    return _checked(gateway, step, target, outcome)


def _cancel_goal(gateway: RobotGateway, step: Step) -> StepEnd:
    """End the step's goal without latching the robot: a zero velocity (the ASTIbot's
    navigation yields to /cmd_vel); if the robot still reports the goal after 2 s, /stop, which
    holds the robot until it is released, and the answer says so."""
    said = f"canceled by the operator during '{step.label()}'"
    profile = gateway.profile
    if profile.kind("navigation") == "action" and not profile.has("status"):
        gateway.cancel_goals()  # Nav2 drives on through a zero velocity: its goal is cancelled
        return StepEnd("canceled", said)
    velocity = profile.name("velocity_command")
    spec = gateway.catalog.topics.get(velocity or "")
    if spec is not None:
        zero = f'ros2 topic pub --once {velocity} {spec.type} "{{}}"'
        gateway.run(zero, YES, source="mission")
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline:
            status = gateway.state().status
            if status is not None and not status.active_goal:
                return StepEnd("canceled", said)
            time.sleep(0.1)
    stop = profile.name("stop")
    if stop is None:
        return StepEnd("canceled", f"{said}; the robot has no stop service: its goal may go on")
    gateway.run(f"ros2 service call {stop} std_srvs/srv/Trigger", YES, source="mission")
    return StepEnd(
        "canceled", f"{said}; the goal went on after a zero velocity, so /stop was called: the "
        "robot holds until the E-STOP is released (ctrl+r)"
    )  # fmt: skip


def _checked(
    gateway: RobotGateway, step: Step, target: tuple[float, float] | None, outcome: str | None
) -> StepEnd:
    """The reported outcome held to the robot's reported pose or docked flag: a step that did
    not happen is never 'succeeded'."""
    state = gateway.state()
    if outcome in ("canceled", "cancelled", "preempted"):
        goal = state.status.active_goal if state.status else ""
        if goal and goal != step.target():
            return StepEnd("replaced", f"replaced by another goal ({goal})")
        return StepEnd("canceled", "the robot reports the goal canceled")
    if outcome not in (None, "succeeded"):
        return StepEnd("failed", f"the robot reports the goal {outcome}")
    if step.kind in ("dock", "undock"):
        if state.status is None:
            return StepEnd("failed", f"the robot reported no docked state after {step.kind}")
        if state.status.docked != (step.kind == "dock"):
            return StepEnd(
                "failed", f"not {step.kind}ed: the robot reports docked {state.status.docked}"
            )
        return StepEnd("succeeded", f"{step.kind}ed")
    if target is not None and state.pose is not None:
        off = math.dist((state.pose.x, state.pose.y), target)
        if off > ARRIVED_M:
            return StepEnd("failed", f"stopped short of {step.target()}: {off:.1f} m from it")
        return StepEnd(
            "succeeded", f"arrived: {step.target()} (x {state.pose.x:.2f}, y {state.pose.y:.2f})"
        )
    if outcome == "succeeded":
        return StepEnd("succeeded", f"the robot reports {step.target()} reached")
    return StepEnd("failed", f"the goal to {step.target()} ended; the robot did not say how")
