"""The robot's state sampled off the UI thread, through the gateway, for whoever shows it."""

from __future__ import annotations

import threading
from collections.abc import Callable

from astiop.robot.gateway import RobotGateway
from astiop.transports.state import RobotEvent, RobotState, TopicStat

Publish = Callable[[RobotState, list[RobotEvent], "list[TopicStat] | None"], None]


class StateSampler(threading.Thread):
    """Reads the robot's state, new events and (about once a second) topic statistics through
    the gateway at `hz`, and hands them to `publish`; a failure is reported once per streak."""

    def __init__(
        self,
        gateway: RobotGateway,
        publish: Publish,
        report: Callable[[str], None],
        hz: float,
        seq: int = 0,
    ):
        super().__init__(name="astiop-sampler", daemon=True)
        self.gateway = gateway
        self.publish = publish
        self.report = report
        self.seq = seq  # events up to here were read at start
        self.pace(hz)
        self.halt = threading.Event()

    def pace(self, hz: float) -> None:
        """Sample at `hz` from the next tick on (topic statistics still about once a second)."""
        self.period, self.every = 1.0 / hz, max(int(hz), 1)

    def run(self) -> None:
        seq, n, failing = self.seq, 0, False
        try:
            while not self.halt.wait(self.period):
                try:
                    state = self.gateway.state()
                    events = self.gateway.events_since(seq)  # the gateway journals them
                    stats = self.gateway.topic_stats() if n % self.every == 0 else None
                    failing = False
                except Exception as exc:  # noqa: BLE001 - say it once, keep sampling
                    if not failing:
                        self.report(f"robot state: {exc}")
                    failing = True
                    continue
                n += 1
                if events:
                    seq = events[-1].seq
                self.publish(state, events, stats)
        finally:
            if self.gateway.store is not None:
                self.gateway.store.close()  # this thread's connection
