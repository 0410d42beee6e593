"""The built-in alerts of one robot, on by default: battery low, fault reported, contact lost and
regained, E-STOP pressed (and by whom), a goal aborted or cancelled by someone else, no progress
toward a goal for N s, a mission failed or interrupted.

They read what the transports already receive (the sampled state and the robot's events) and
the missions in the store; each is written through `Alerts.fire`, which keeps one alert per
event across processes on one database (`store/watches.py`)."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Protocol

from astiop.transports.state import RobotEvent, RobotState
from astiop.watches.model import FIELDS, OPS, Sample, Watch

KINDS = (
    "battery_low", "fault", "contact_lost", "contact_regained", "estop", "goal_aborted",
    "goal_canceled", "no_progress", "mission_failed", "mission_interrupted",
)  # fmt: skip
PROGRESS_M = 0.10  # nearer the goal along its plan by this much is progress
MOVED_M = 0.5  # and so is moving this far (Nav2's progress checker's required_movement_radius)
OPERATOR_STOP_S = 5.0  # a cancel this soon after an astiop stop or cancel is the operator's own
MISSIONS_S = 1.0  # the store's missions are read this often
GOING = ("navigating", "blocked", "docking")
# a goal's end as each transport says it: the simulator's "goal 3 aborted: why", rclpy's and
# ros2cli's "goal finished: ABORTED (why)" and "goal canceled", and another client's Nav2 goal
# "goal 1a2b3c4d aborted (another client's goal)" (transports/goal_ends.py)
GOAL_END = re.compile(
    r"^goal (?:finished: )?(?:(?P<id>[0-9a-f]+) )?(?P<how>aborted|canceled)(?:: | \()?(?P<why>.*?)\)?$",
    re.IGNORECASE,
)


class Alerts(Protocol):
    """Where a built-in alert goes (the evaluator: the store, once per event)."""

    def fire(
        self, name: str, kind: str, message: str, reading: str | None = None,
        age: float | None = None, *, paired_with: str | None = None,
    ) -> None: ...  # fmt: skip

    def cleared(self, name: str, settled: bool = False) -> None: ...


@dataclass
class Edge:
    """One condition over time: `since` it has held (None: it does not), `on` once it has held
    long enough (None: not seen yet)."""

    since: float | None = None
    on: bool | None = None

    def update(self, holds: bool | None, clear: bool, now: float, hold_s: float = 0.0) -> str:
        """'rise' when the condition has just held for `hold_s`, 'fall' when it has cleared,
        'first' when it is first seen clear, '' otherwise or without a reading (`holds` None)."""
        if holds is None:
            return ""
        if self.on:
            if clear:
                self.on, self.since = False, None
                return "fall"
            return ""
        if holds:
            self.since = now if self.since is None else self.since
            if now - self.since >= hold_s:
                self.on = True
                return "rise"
            return ""
        first = self.on is None
        self.on, self.since = False, None
        return "first" if first else ""


def compare(watch: Watch, value: float) -> tuple[bool, bool]:
    """Whether the condition holds, and whether it has cleared (back over by the margin)."""
    holds = OPS[watch.op](value, watch.threshold)
    margin = FIELDS[watch.field].margin
    back = watch.threshold + margin if watch.op in ("<", "<=") else watch.threshold - margin
    return holds, not OPS[watch.op](value, back)


def goal_end(event: RobotEvent) -> tuple[str, str, str] | None:
    """(how, why, goal id or '') of a goal's end said as an event; None for any other event."""
    m = GOAL_END.match(event.message) if event.kind == "goal" else None
    if m is None:
        return None
    return m["how"].lower(), m["why"].strip(), m["id"] or ""


class Progress:
    """Whether a goal is being approached: nearer along its plan by PROGRESS_M, or moved MOVED_M
    from where it last progressed (around an obstacle, or without a plan)."""

    def __init__(self) -> None:
        self.goal: str | None = None
        self.best: float = math.inf
        self.anchor: tuple[float, float] | None = None
        self.at = 0.0

    def stalled_s(self, state: RobotState, now: float) -> float | None:
        """Seconds without progress while a goal runs; None when none runs."""
        st = state.status
        goal = st.active_goal if st is not None and st.state in GOING else ""
        if not goal:
            self.goal = None
            return None
        left = state.distance_remaining
        here = (state.pose.x, state.pose.y) if state.pose is not None else None
        if goal != self.goal:
            self.goal, self.best, self.anchor, self.at = goal, math.inf, here, now
        nearer = left is not None and left <= self.best - PROGRESS_M
        moved = (
            here is not None and self.anchor is not None and math.dist(here, self.anchor) >= MOVED_M
        )
        if nearer or moved:
            self.best = left if left is not None else self.best
            self.anchor, self.at = here, now
        return now - self.at


class BuiltinAlerts:
    def __init__(
        self,
        store,
        robot: str,
        alerts: Alerts,
        *,
        battery_low: float,
        no_progress_s: float,
        mission_robot: str | None = None,
        pressed_by: Callable[[], str] | None = None,
    ):
        self.store = store
        self.robot = robot
        self.alerts = alerts
        self.battery_low = Watch("battery", "<", battery_low, repeat="every", robot=robot)
        self.no_progress_s = no_progress_s
        self.mission_robot = robot if mission_robot is None else mission_robot
        self.pressed_by = pressed_by
        self.threshold: Callable[[], float] | None = None  # the battery's, read at each step
        self._edges: dict[str, Edge] = {}
        self._progress = Progress()
        self._missions_at = -math.inf
        self._ended_before: set[int] | None = None  # missions that ended before it looked

    def _name(self, what: str) -> str:
        return f"{self.robot}/{what}"

    def _edge(self, name: str) -> Edge:
        return self._edges.setdefault(name, Edge())

    def step(
        self, state: RobotState, ages: Mapping[str, float], now: float,
        events: Sequence[RobotEvent] = (),
    ) -> None:  # fmt: skip
        self._contact(state, now)
        self._missions()
        if state.lost_s is not None:
            return  # nothing else it last said holds
        battery = FIELDS["battery"].read(Sample(state), self.battery_low)
        if battery is not None and self.threshold is not None:
            low = self.threshold()
            if low != self.battery_low.threshold:
                self.battery_low = replace(self.battery_low, threshold=low)
        if battery is not None:
            holds, clear = compare(self.battery_low, battery)
            self._condition(
                "battery_low", holds, clear, now,
                f"battery low: {battery:.1f} % (below {self.battery_low.threshold:g} %)",
                f"{battery:.1f} %", ages.get("battery"),
            )  # fmt: skip
        if state.status is not None:
            fault = state.status.fault or ("fault" if state.status.state == "fault" else "")
            self._condition(
                "fault", bool(fault), not fault, now, f"fault reported: {fault}", fault,
                ages.get("status"),
            )  # fmt: skip
        engaged = state.e_stopped
        by = self._estop_by() if engaged and not self._edge(self._name("estop")).on else ""
        said = f"E-STOP engaged{f' by {by}' if by else ''}"
        self._condition("estop", engaged, not engaged, now, said, None, None)
        for event in events:
            self._goal_ended(event, state)
        stalled = self._progress.stalled_s(state, now)
        going = stalled is not None and not engaged
        held = (stalled or 0.0) if going else 0.0
        self._condition(
            "no_progress", held >= self.no_progress_s, held == 0.0, now,
            f"no progress toward {self._progress.goal} for {held:.0f} s", f"{held:.0f} s",
            ages.get("status"),
        )  # fmt: skip

    def _contact(self, state: RobotState, now: float) -> None:
        lost = state.lost_s is not None
        name = self._name("contact_lost")
        edge = self._edge(name).update(lost, not lost, now)
        if edge == "rise":
            self.alerts.fire(
                name, "contact_lost",
                f"contact lost: the robot has not been heard for {state.lost_s:.1f} s",
                f"{state.lost_s:.1f} s",
            )  # fmt: skip
        elif edge == "fall":
            self.alerts.fire(
                self._name("contact_regained"), "contact_regained", "contact regained",
                paired_with=name,
            )  # fmt: skip
            self.alerts.cleared(name)
        elif edge == "first":
            self.alerts.cleared(name, settled=True)

    def _condition(self, kind, holds, clear, now, message, reading, age) -> None:
        name = self._name(kind)
        edge = self._edge(name).update(holds, clear, now)
        if edge == "rise":
            self.alerts.fire(name, kind, message, reading, age)
        elif edge in ("fall", "first"):
            self.alerts.cleared(name, settled=edge == "first")

    def _estop_by(self) -> str:
        by = self.pressed_by() if self.pressed_by is not None else ""
        if by:
            return by
        return (self.store.estop_latch() or {}).get("by") or ""

    # -- a goal's end --------------------------------------------------------------------------
    def _goal_ended(self, event: RobotEvent, state: RobotState) -> None:
        end = goal_end(event)
        if end is None:
            return
        how, why, goal_id = end
        if how == "canceled" and self._operators_cancel(why, state):
            return
        # one goal's end is one event: the simulator numbers its goals; a goal a live robot
        # ran for this process is said by this process alone (its event's number)
        key = f"goal:{goal_id}" if goal_id else f"goal@{time.time():.0f}#{event.seq}"
        kind = "goal_aborted" if how == "aborted" else "goal_canceled"
        words = "aborted" if how == "aborted" else "cancelled by someone else"
        name = self._name(key)
        # a simulator numbers its goals anew in each run: a goal of this number said a while
        # ago was another goal (said just now, by another process, it is this one)
        self.alerts.cleared(name, settled=True)
        self.alerts.fire(name, kind, f"goal {words}{f': {why}' if why else ''}", why or None)

    def _operators_cancel(self, why: str, state: RobotState) -> bool:
        """A cancel astiop's operator made: the E-STOP (its own alert), a new goal in place of
        the old one, or a stop or cancel journaled on this database a moment before."""
        if state.e_stopped or why.startswith(("replaced by", "canceled by the operator")):
            return True
        return bool(self.store.operator_stopped_since(time.time() - OPERATOR_STOP_S))

    # -- missions ------------------------------------------------------------------------------
    def _missions(self) -> None:
        mono = time.monotonic()
        if mono - self._missions_at < MISSIONS_S:
            return
        self._missions_at = mono
        ended = self.store.missions_ended_badly(self.mission_robot)
        if self._ended_before is None:
            self._ended_before = {m["id"] for m in ended}
        for m in ended:
            if m["id"] in self._ended_before:
                continue
            kind = "mission_failed" if m["status"] == "failed" else "mission_interrupted"
            said = f"mission {m['id']} {m['status']}: {m['reason'] or m['request']}"
            key = self._name(f"mission:{m['id']}:{m['status']}")
            self.alerts.fire(key, kind, said, m["status"])
