"""The watches of one robot and its built-in alerts, evaluated against each sampled state.

Each condition keeps its own edge here (since when it holds, whether it fired); the event it
fires is written through the store, which keeps one alert per event across processes
(`store/watches.py`): two evaluators on one database write one alert.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence

from astiop.transports.state import RobotEvent, RobotState
from astiop.watches.builtins import KINDS, BuiltinAlerts, Edge, Progress
from astiop.watches.builtins import compare as _compare
from astiop.watches.model import Sample, Watch

RELOAD_S = 1.0  # the store's watches are read again this often (added, removed, disarmed)
BUILTIN_KINDS = KINDS


class Evaluator:
    def __init__(
        self,
        store,
        robot: str = "",
        *,
        battery_low: float = 20.0,
        builtins: bool = True,
        no_progress_s: float = 30.0,
        mission_robot: str | None = None,
        pressed_by: Callable[[], str] | None = None,
    ):
        self.store = store
        self.robot = robot
        self.builtins = builtins
        self.builtin = BuiltinAlerts(
            store, robot, _Writer(self), battery_low=battery_low, no_progress_s=no_progress_s,
            mission_robot=mission_robot, pressed_by=pressed_by,
        )  # fmt: skip
        self._fired: list[dict] = []
        self.watches: list[Watch] = []
        self._edges: dict[str, Edge] = {}
        self._progress = Progress()  # the no-progress watches' count, as the built-in's
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
        self,
        state: RobotState,
        ages: Mapping[str, float] | None = None,
        now: float | None = None,
        events: Sequence[RobotEvent] = (),
    ) -> list[dict]:
        """The alerts this state fired and this process wrote first (new rows)."""
        now = time.monotonic() if now is None else now
        if time.monotonic() - self._loaded_at >= RELOAD_S:
            self.reload()
        ages = ages or {}
        fired: list[dict] = []
        self._fired = fired
        if self.builtins:
            self.builtin.step(state, ages, now, events)
        stalled = None
        if any(w.field == "no_progress" for w in self.watches):
            stalled = self._progress.stalled_s(state, now)
        # no goal is stalled while the E-STOP holds (the built-in alert's rule too)
        sample = Sample(state, None if state.e_stopped or state.lost_s is not None else stalled)
        for watch in list(self.watches):
            self._watch(watch, sample, ages, now, fired)
        return fired

    # -- the operator's watches ------------------------------------------------------------
    def _watch(self, watch: Watch, sample: Sample, ages, now: float, fired: list) -> None:
        value = watch.spec.read(sample, watch)
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
        elif edge in ("fall", "first"):
            self.store.end_episode(name, settled=edge == "first")

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


class _Writer:
    """The built-in alerts' events written through the evaluator's store, each new one kept
    among this step's fired alerts."""

    def __init__(self, evaluator: Evaluator):
        self.ev = evaluator

    def fire(self, name, kind, message, reading=None, age=None, *, paired_with=None) -> None:
        self.ev._fire(self.ev._fired, name, kind, message, reading, age, paired_with=paired_with)

    def cleared(self, name: str, settled: bool = False) -> None:
        self.ev.store.end_episode(name, settled=settled)
