"""`astiop watch run`: the evaluator on one robot's state, sampled through the gateway, with no
console; each new alert handed to `on_alert` (the store has it already)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from astiop.robot.gateway import RobotGateway
from astiop.watches.evaluator import Evaluator
from astiop.watches.model import FIELDS

log = logging.getLogger("astiop.watches")
AGE_ROLES = sorted({r for f in FIELDS.values() for r in f.roles} | {"status"})


ALWAYS_READ = ("battery", "status")  # the built-in alerts' roles: always watched anyway


def reading_ages(gateway: RobotGateway, t: float, evaluator: Evaluator) -> dict[str, float]:
    """How old each role's latest message is, on the robot's clock (its `RobotState.t`): the
    roles the armed watches and the built-in alerts read, and no other (asking a live robot
    for a topic's time subscribes to it: an idle console does not watch its 50 Hz /odom)."""
    wanted = set(ALWAYS_READ) | {w.role for w in evaluator.watches}
    topics = {role: gateway.profile.name(role) for role in AGE_ROLES if role in wanted}
    times = gateway.message_times([n for n in topics.values() if n])
    return {role: max(0.0, t - times[name]) for role, name in topics.items() if name in times}


class WatchRunner:
    def __init__(
        self,
        gateway: RobotGateway,
        evaluator: Evaluator,
        on_alert: Callable[[dict], None],
        report: Callable[[str], None],
        hz: float = 10.0,
    ):
        self.gateway = gateway
        self.evaluator = evaluator
        self.on_alert = on_alert
        self.report = report
        self.period = 1.0 / hz
        self.halt = threading.Event()

    def run(self) -> None:
        """Until `halt` is set; a failing read or write is said once per streak."""
        failing = False
        while not self.halt.wait(self.period):
            try:
                state = self.gateway.state()
                alerts = self.evaluator.step(
                    state, reading_ages(self.gateway, state.t, self.evaluator)
                )
                failing = False
            except Exception as exc:  # noqa: BLE001 - say it once, keep watching
                if not failing:
                    self.report(f"watching: {exc}")
                failing = True
                continue
            for alert in alerts:
                self.on_alert(alert)


class Watching:
    """The evaluator on samples taken elsewhere (the console's sampler thread): a failure (a
    read-only or busy database) is logged once per streak, never raised into the sampler."""

    def __init__(self, gateway: RobotGateway, evaluator: Evaluator):
        self.gateway = gateway
        self.evaluator = evaluator
        self._failing = False

    def step(self, state) -> list[dict]:
        try:
            alerts = self.evaluator.step(state, reading_ages(self.gateway, state.t, self.evaluator))
        except Exception as exc:  # noqa: BLE001 - the console goes on showing the robot
            if not self._failing:
                log.info("watches not evaluated: %s", exc)
            self._failing = True
            return []
        self._failing = False
        return alerts
