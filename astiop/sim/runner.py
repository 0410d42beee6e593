"""Runs a simulator in its own thread at real time (or ×N) for the console."""

from __future__ import annotations

import threading
import time

from astiop.sim.fleet import SimFleet
from astiop.sim.simulator import Simulator


class SimRunner:
    def __init__(self, sim: Simulator | SimFleet, speed: float = 1.0, period_s: float = 0.02):
        self.sim = sim
        self.speed = speed
        self.period_s = period_s
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> SimRunner:
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, name="astiop-sim", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def _loop(self) -> None:
        last = time.perf_counter()
        while not self._stop.is_set():
            now = time.perf_counter()
            elapsed, last = now - last, now
            # never try to catch up more than a quarter second after a stall
            self.sim.step(min(elapsed, 0.25) * self.speed)
            spent = time.perf_counter() - now
            self._stop.wait(max(0.0, self.period_s - spent))
