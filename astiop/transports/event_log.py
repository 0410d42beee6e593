"""The robot's events as a live ROS 2 backend notes them: numbered, on the backend's clock, and
the changes of the robot's reported state and fault."""

from __future__ import annotations

import threading
import time
from collections import deque

from astiop.transports.state import RobotEvent


class EventLog:
    def __init__(self, t0: float, keep: int = 500):
        self.t0 = t0  # time.monotonic() of the backend's start: the events' clock
        self.seq = 0
        self._events: deque[RobotEvent] = deque(maxlen=keep)
        self._lock = threading.Lock()
        self._state: str | None = None
        self._fault = ""

    def add(self, kind: str, severity: str, message: str) -> None:
        with self._lock:
            self.seq += 1
            t = time.monotonic() - self.t0
            self._events.append(RobotEvent(self.seq, t, kind, severity, message))

    def since(self, seq: int) -> list[RobotEvent]:
        with self._lock:
            return [e for e in self._events if e.seq > seq]

    def status(self, state: str, fault: str) -> None:
        """A /robot_status arrived: an event for a new state word, and one for a new fault."""
        before, self._state = self._state, state
        if before is not None and before != state:
            severity = "error" if state in ("fault", "e_stopped") else "info"
            self.add("state", severity, f"{before} -> {state}")
        if fault and fault != self._fault:
            self.add("fault", "error", fault)
        self._fault = fault


class EstopWork:
    """What the last E-STOP started in the background, and the failures it said, for a process
    about to exit (`RobotTransport.settle_estop`)."""

    def __init__(self, events: EventLog):
        self.events = events
        self._seq = 0
        self._said: set[str] = set()
        self._threads: list[threading.Thread] = []

    def begin(self) -> None:
        self._seq, self._said, self._threads = self.events.seq, set(), []

    def start(self, target, name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def said(self, failures: list[str]) -> None:
        """The failures the E-STOP returns, logged; `settle` says only what came after."""
        for f in failures:
            self.events.add("estop", "error", f)
        self._said = set(failures)

    def settle(self, timeout_s: float) -> list[str]:
        """Wait for the threads (each ends by its own timeout, `timeout_s`: a moment more to hear
        how), then the E-STOP failures said since it began that it did not already return."""
        deadline = time.monotonic() + timeout_s + 1.0
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))
        return [
            e.message
            for e in self.events.since(self._seq)
            if e.kind == "estop" and e.severity != "info" and e.message not in self._said
        ]


LOST_S = 2.0  # none of the robot's state topics (10 Hz and faster among them) for this long


class Contact:
    """Whether the robot is heard: silent for `silent_s` (none of its state topics came), it is
    lost, said once; heard again, reconnected, said once. Never heard is not lost (not yet)."""

    def __init__(self, events: EventLog, silent_s: float = LOST_S, on_return=None):
        self.events = events
        self.silent_s = silent_s
        self.on_return = on_return  # what a transport redoes once the robot is back
        self._lost = False
        self._lock = threading.Lock()

    def check(self, ages: list[float]) -> float | None:
        """The seconds since the robot was last heard when it is lost, else None; `ages` are
        its topics' last messages' ages (inf: none came yet)."""
        heard = [a for a in ages if a != float("inf")]
        age = min(heard) if heard else None
        lost = age is not None and age > self.silent_s
        with self._lock:
            changed, self._lost = lost != self._lost, lost
        if changed and lost:
            self.events.add(
                "robot", "error", f"lost contact with the robot: no message for {self.silent_s:g} s"
            )
        elif changed:
            self.events.add("robot", "info", "reconnected: the robot is publishing again")
            if self.on_return is not None:
                self.on_return()
        return age if lost else None
