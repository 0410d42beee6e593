"""Every astiop process follows the shared E-STOP latch while it has anything in flight, with no
screen asking for the state (`astiop exec`, `astiop mcp`, a chat turn, a benchmark, a recording).

The latch lives in the store, so the watcher asks the store: SQLite's `PRAGMA data_version` on
its own connection changes when any other process commits, and costs a few microseconds, so it is
looked at 50 times a second while something moves the robot and not at all otherwise. A file lock
or inotify would need a second home for the latch (and inotify is Linux only); a socket, a server.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from astiop.store import Store
from astiop.transports.inflight import InFlight

POLL_S = 0.02  # while in flight: another process's latch is seen within this
HELD_POLL_S = 0.2  # while only held: a release elsewhere is followed within this
IDLE_WAIT_S = 1.0  # how often an idle watcher wakes to see whether it was closed

log = logging.getLogger("astiop.robot")


class LatchWatcher:
    def __init__(self, store: Store, inflight: InFlight, follow: Callable[[], object]):
        self.store = store
        self.inflight = inflight
        self.follow = follow  # reads the latch and makes this process's robot follow it
        self._closed = threading.Event()
        self._said: set[str] = set()
        self._thread = threading.Thread(target=self._loop, name="estop-latch", daemon=True)

    def start(self) -> LatchWatcher:
        self._thread.start()
        return self

    def close(self) -> None:
        self._closed.set()
        self.inflight.wake()

    def _loop(self) -> None:
        try:
            while not self._closed.is_set():
                if self.inflight.wait_watched(IDLE_WAIT_S) and not self._closed.is_set():
                    self._watch()
        finally:
            self.store.close()  # this thread's connection

    def _watch(self) -> None:
        seen = None
        while self.inflight.watched and not self._closed.is_set():
            try:
                version = self.store.latch_version()
                if version != seen:
                    self.follow()
                    seen = version  # only once followed: a failed look is looked at again
            except Exception as exc:  # noqa: BLE001 - said once; the next look may work
                self._say(f"the E-STOP latch could not be read: {exc}")
            self._closed.wait(POLL_S if self.inflight.busy else HELD_POLL_S)

    def _say(self, message: str) -> None:
        if message not in self._said:
            self._said.add(message)
            log.error(message)
