"""The simulator's time and what happened in it: the clock every helper reads (only the
physics step moves it) and the event log it stamps."""

from __future__ import annotations

import collections
from dataclasses import dataclass

from astiop.sim.state import Event


@dataclass
class Clock:
    dt: float  # s, one physics step
    tick: int = 0  # physics steps so far
    t: float = 0.0  # s, `tick * dt`


class SimEvents:
    """The robot's last 500 events, numbered from 1, each stamped with the clock's time."""

    def __init__(self, clock: Clock) -> None:
        self._clock = clock
        self._log: collections.deque[Event] = collections.deque(maxlen=500)
        self.seq = 0  # the last event's number

    def say(self, kind: str, message: str, severity: str = "info") -> None:
        self.seq += 1
        self._log.append(Event(self.seq, self._clock.t, kind, severity, message))

    def since(self, seq: int) -> list[Event]:
        return [e for e in self._log if e.seq > seq]
