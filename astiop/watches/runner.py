"""`astiop watch run`: the evaluator on one robot's state, sampled through the gateway, with no
console; each new alert handed to `on_alert` (the store has it already)."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from astiop.robot.gateway import RobotGateway
from astiop.watches.evaluator import Evaluator
from astiop.watches.model import FIELDS
from astiop.watches.reactions import react

log = logging.getLogger("astiop.watches")
AGE_ROLES = sorted({r for f in FIELDS.values() for r in f.roles} | {"status"})


NEW_S = 0.01  # how often `watch run` looks for a new reading
ALWAYS_READ = ("battery", "status")  # the built-in alerts' roles: always watched anyway
BATTERY_LOW = 20.0  # %, where neither the settings nor the robot's profile say


def battery_low(gateway: RobotGateway, configured: float | None) -> float:
    """The settings' threshold, else the robot profile's, else BATTERY_LOW."""
    if configured is not None:
        return configured
    profile = gateway.profile
    low = profile.limits.battery_low if profile is not None else None
    return BATTERY_LOW if low is None else low


def pressed_by(gateway: RobotGateway) -> str:
    """Who pressed the E-STOP, as the robot's graph says it (never waits: '' until heard), else
    as the database latched it: the robot's own latch (a fleet's, by its namespace), or every
    robot's."""
    latch = gateway.station_latch
    if latch is not None and latch.wait_ready(0) and latch.engaged and latch.press is not None:
        return latch.press.words
    store = gateway.store
    if store is None:
        return ""
    own = store.robot_latch(gateway.latch_key) if gateway.latch_key else None
    return str((own or store.estop_latch() or {}).get("by") or "")


def make_evaluator(gateway: RobotGateway, store, settings, robot: str = "") -> Evaluator:
    """The watches and built-in alerts of the gateway's robot (`robot`: its fleet name)."""
    w = settings.watches
    ev = Evaluator(
        store, robot, battery_low=battery_low(gateway, w.battery_low), builtins=w.builtins,
        no_progress_s=w.no_progress_s, mission_robot=gateway.label,
        pressed_by=lambda: pressed_by(gateway),
    )  # fmt: skip
    if w.battery_low is None:  # the profile is matched once the robot is found: read it then
        ev.builtin.threshold = lambda: battery_low(gateway, None)
    return ev


def reading_ages(gateway: RobotGateway, t: float, evaluator: Evaluator) -> dict[str, float]:
    """How old each role's latest message is, on the robot's clock (its `RobotState.t`): the
    roles the armed watches and the built-in alerts read, and no other (asking a live robot
    for a topic's time subscribes to it: an idle console does not watch its 50 Hz /odom)."""
    wanted = set(ALWAYS_READ) | {w.role for w in evaluator.watches}
    topics = {role: gateway.profile.name(role) for role in AGE_ROLES if role in wanted}
    times = gateway.message_times([n for n in topics.values() if n])
    return {role: max(0.0, t - times[name]) for role, name in topics.items() if name in times}


class WatchRunner(threading.Thread):
    """One robot's watches and built-in alerts: started as a thread (a console), or `run()` on
    the caller's (`astiop watch run`)."""

    def __init__(
        self,
        gateway: RobotGateway,
        evaluator: Evaluator,
        on_alert: Callable[[dict], object],  # with its reaction's outcome, if it has one
        report: Callable[[str], object],  # a failing read or write, once per streak
        hz: float = 10.0,
    ):
        super().__init__(name="watches", daemon=True)
        self.gateway = gateway
        self.evaluator = evaluator
        self.on_alert = on_alert
        self.report = report
        self.period = 1.0 / hz
        self.halt = threading.Event()

    def run(self) -> None:
        """Until `halt` is set; a failing read or write is said once per streak. Evaluated at
        `hz`, and at once when a reading the watches read arrives (looked for every NEW_S): a
        watch fires within NEW_S of its reading, not within a whole period."""
        failing = False
        seq = self.gateway.state().event_seq
        last: dict[str, float] = {}
        due = time.monotonic()
        while not self.halt.wait(NEW_S):
            try:
                times = self._times()
                if times == last and time.monotonic() < due:
                    continue
                last, due = times, time.monotonic() + self.period
                state = self.gateway.state()
                events = self.gateway.events_since(seq)
                seq = events[-1].seq if events else seq
                ages = reading_ages(self.gateway, state.t, self.evaluator)
                alerts = self.evaluator.step(state, ages, now=state.t, events=events)
                failing = False
            except Exception as exc:  # noqa: BLE001 - say it once, keep watching
                if not failing:
                    self.report(f"watching: {exc}")
                failing = True
                continue
            for alert in alerts:  # this process wrote it first: its reaction is this process's
                said = react(self.gateway, self.evaluator.store, alert, state.e_stopped)
                if said is not None:
                    alert["reaction"] = said
                self.on_alert(alert)

    def _times(self) -> dict[str, float]:
        """When each topic the watches and built-in alerts read last brought a message."""
        wanted = set(ALWAYS_READ) | {w.role for w in self.evaluator.watches}
        names = [self.gateway.profile.name(r) for r in wanted] if self.gateway.profile else []
        return self.gateway.message_times([n for n in names if n])


class Watching:
    """The evaluator on samples taken elsewhere (the console's sampler thread): a failure (a
    read-only or busy database) is logged once per streak, never raised into the sampler."""

    def __init__(self, gateway: RobotGateway, evaluator: Evaluator):
        self.gateway = gateway
        self.evaluator = evaluator
        self._failing = False

    def step(self, state, events=()) -> list[dict]:
        try:
            ages = reading_ages(self.gateway, state.t, self.evaluator)
            # on the robot's clock: a paused simulator's goal stalls no watch
            alerts = self.evaluator.step(state, ages, now=state.t, events=events)
        except Exception as exc:  # noqa: BLE001 - the console goes on showing the robot
            if not self._failing:
                log.info("watches not evaluated: %s", exc)
            self._failing = True
            return []
        self._failing = False
        for alert in alerts:  # this process wrote it first: its reaction is this process's
            said = react(self.gateway, self.evaluator.store, alert, state.e_stopped)
            if said is not None:
                alert["reaction"] = said
        return alerts


class FleetWatching(threading.Thread):
    """Every robot of a fleet console's watch (`gateways()`: name -> gateway, as they are
    reached), evaluated on one thread at `hz`; new alerts handed to `on_alert`."""

    def __init__(self, gateways, store, settings, on_alert: Callable[[list[dict]], object]):
        super().__init__(name="fleet-watches", daemon=True)
        self.gateways = gateways
        self.store = store
        self.settings = settings
        self.on_alert = on_alert
        self.period = 1.0 / settings.watches.hz
        self.halt = threading.Event()
        self._each: dict[str, tuple[Watching, int]] = {}

    def run(self) -> None:
        while not self.halt.wait(self.period):
            for name, gateway in list(self.gateways().items()):
                try:  # one robot not read never ends the others' watching
                    if name not in self._each:
                        ev = make_evaluator(gateway, self.store, self.settings, name)
                        self._each[name] = (Watching(gateway, ev), gateway.state().event_seq)
                    watching, seq = self._each[name]
                    state, events = gateway.state(), gateway.events_since(seq)
                except Exception:  # noqa: BLE001 - its Fleet row says it is not read
                    continue
                self._each[name] = (watching, events[-1].seq if events else seq)
                alerts = watching.step(state, events)
                if alerts:
                    self.on_alert(alerts)
