"""`astiop serve`'s headless watcher: `astiop watch run` on the tabs' robot, so watches and
built-in alerts are evaluated with no tab open (each tab's console evaluates them too: the
database writes each alert once). One that ends is said in the server's log and started again
after a pause that grows while it keeps ending, until the server stops."""

from __future__ import annotations

import logging
import subprocess
import threading
import time
from collections.abc import Callable

log = logging.getLogger("astiop.serve")
FIRST_PAUSE_S, LAST_PAUSE_S = 2.0, 60.0
SETTLED_S = 60.0  # one that ran this long before it ended starts again after the first pause


class Watcher:
    def __init__(
        self, start: Callable[[], subprocess.Popen], end: Callable[[subprocess.Popen], None]
    ):
        """`start`: the process started; `end`: how it is ended when the server stops."""
        self._start, self._end = start, end
        self._halt = threading.Event()
        self._lock = threading.Lock()  # the process, against close()
        self._process: subprocess.Popen | None = None
        self.restarts = 0
        self._thread = threading.Thread(target=self._keep, name="watch-run", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _keep(self) -> None:
        pause = FIRST_PAUSE_S
        while True:
            with self._lock:
                if self._halt.is_set():
                    return
                process = self._process = self._start()
            began = time.monotonic()
            code = process.wait()
            if self._halt.is_set():
                return
            if time.monotonic() - began > SETTLED_S:
                pause = FIRST_PAUSE_S
            log.warning(
                "watch run ended (exit code %s): watches are evaluated only in open tabs until it "
                "starts again in %.0f s",
                code,
                pause,
            )
            if self._halt.wait(pause):
                return
            self.restarts += 1
            pause = min(pause * 2, LAST_PAUSE_S)

    def close(self) -> None:
        self._halt.set()
        with self._lock:
            process = self._process
        if process is not None:
            self._end(process)
        self._thread.join(5)
