"""The watches of one robot and its built-in alerts, evaluated against each sampled state.

Each condition keeps its own edge here (since when it holds, whether it fired); the event it
fires is written through the store, which keeps one alert per event across processes
(`store/watches.py`): two evaluators on one database write one alert.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

from astiop.transports.state import RobotState
from astiop.watches.model import FIELDS, OPS, Watch

RELOAD_S = 1.0  # the store's watches are read again this often (added, removed, disarmed)
BUILTIN_KINDS = ("battery_low", "fault", "contact_lost", "contact_regained", "estop")


@dataclass
class Edge:
    """One condition over time: `since` it has held (None: it does not), `on` once it has held
    long enough (None: not seen yet)."""

    since: float | None = None
    on: bool | None = None

    def update(self, holds: bool | None, clear: bool, now: float, hold_s: float = 0.0) -> str:
        """'rise' when the condition has just held for `hold_s`, 'fall' when it has cleared
        (or is first seen clear), '' otherwise or without a reading (`holds` None)."""
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
        return "fall" if first else ""


def _compare(watch: Watch, value: float) -> tuple[bool, bool]:
    """Whether the condition holds, and whether it has cleared (back over by the margin)."""
    holds = OPS[watch.op](value, watch.threshold)
    margin = FIELDS[watch.field].margin
    back = watch.threshold + margin if watch.op in ("<", "<=") else watch.threshold - margin
    return holds, not OPS[watch.op](value, back)


class Evaluator:
    def __init__(
        self,
        store,
        robot: str = "",
        *,
        battery_low: float = 20.0,
        builtins: bool = True,
    ):
        self.store = store
        self.robot = robot
        self.battery_low = Watch("battery", "<", battery_low, repeat="every", robot=robot)
        self.builtins = builtins
        self.watches: list[Watch] = []
        self._edges: dict[str, Edge] = {}
        self._loaded_at = -math.inf

    def _name(self, what: str) -> str:
        return f"{self.robot}/{what}"

    def _edge(self, name: str) -> Edge:
        return self._edges.setdefault(name, Edge())

    def reload(self) -> None:
        rows = self.store.list_watches(robot=self.robot, armed_only=True)
        self.watches = [Watch.from_row(r) for r in rows]
        self._loaded_at = time.monotonic()

    def step(
        self, state: RobotState, ages: Mapping[str, float] | None = None, now: float | None = None
    ) -> list[dict]:
        """The alerts this state fired and this process wrote first (new rows)."""
        now = time.monotonic() if now is None else now
        if time.monotonic() - self._loaded_at >= RELOAD_S:
            self.reload()
        ages = ages or {}
        fired: list[dict] = []
        if self.builtins:
            self._builtins(state, ages, now, fired)
        for watch in list(self.watches):
            self._watch(watch, state, ages, now, fired)
        return fired

    # -- the operator's watches ------------------------------------------------------------
    def _watch(self, watch: Watch, state: RobotState, ages, now: float, fired: list) -> None:
        value = watch.spec.read(state)
        if value is None:
            return
        holds, clear = _compare(watch, value)
        name = self._name(f"watch:{watch.id}")
        edge = self._edge(name).update(holds, clear, now, watch.duration_s)
        if edge == "rise":
            self._fire(
                fired, name, "watch", f"{watch.condition()}: {watch.reading(value)}",
                watch.reading(value), ages.get(watch.role), watch.id, watch.repeat == "once",
            )  # fmt: skip
            if watch.repeat == "once":
                self.watches.remove(watch)  # disarmed, by this process or the one first
        elif edge == "fall":
            self.store.end_episode(name)

    # -- the built-in alerts ---------------------------------------------------------------
    def _builtins(self, state: RobotState, ages, now: float, fired: list) -> None:
        lost = state.lost_s is not None
        edge = self._edge(self._name("contact_lost")).update(lost, not lost, now)
        if edge == "rise":
            self._fire(
                fired, self._name("contact_lost"), "contact_lost",
                f"contact lost: the robot has not been heard for {state.lost_s:.1f} s",
                f"{state.lost_s:.1f} s",
            )  # fmt: skip
        elif edge == "fall":
            self._fire(
                fired, self._name("contact_regained"), "contact_regained", "contact regained",
                paired_with=self._name("contact_lost"),
            )  # fmt: skip
            self.store.end_episode(self._name("contact_lost"))
        if lost:
            return  # nothing else it last said holds
        battery = FIELDS["battery"].read(state)
        if battery is not None:
            holds, clear = _compare(self.battery_low, battery)
            self._builtin(
                "battery_low", holds, clear, now, fired,
                f"battery low: {battery:.1f} % (below {self.battery_low.threshold:g} %)",
                f"{battery:.1f} %", ages.get("battery"),
            )  # fmt: skip
        if state.status is not None:
            fault = state.status.fault or ("fault" if state.status.state == "fault" else "")
            self._builtin(
                "fault", bool(fault), not fault, now, fired, f"fault reported: {fault}", fault,
                ages.get("status"),
            )  # fmt: skip
        engaged = state.e_stopped
        by = self._estop_by() if engaged and not self._edge(self._name("estop")).on else ""
        self._builtin(
            "estop", engaged, not engaged, now, fired,
            f"E-STOP engaged{f' by {by}' if by else ''}", None, None,
        )  # fmt: skip

    def _builtin(self, kind, holds, clear, now, fired, message, reading, age) -> None:
        name = self._name(kind)
        edge = self._edge(name).update(holds, clear, now)
        if edge == "rise":
            self._fire(fired, name, kind, message, reading, age)
        elif edge == "fall":
            self.store.end_episode(name)

    def _estop_by(self) -> str:
        latch = self.store.robot_latch(self.robot) if self.robot else self.store.estop_latch()
        return (latch or {}).get("by") or ""

    def _fire(
        self,
        fired: list,
        name: str,
        kind: str,
        message: str,
        reading: str | None = None,
        age: float | None = None,
        watch_id: int | None = None,
        disarm: bool = False,
        paired_with: str | None = None,
    ) -> None:
        alert_id = self.store.fire_alert(
            name, robot=self.robot, kind=kind, message=message, reading=reading,
            reading_age_s=age, watch_id=watch_id, disarm=disarm, paired_with=paired_with,
        )  # fmt: skip
        if alert_id is not None:
            fired.append(self.store.alert(alert_id))
