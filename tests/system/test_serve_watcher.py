"""`astiop serve`'s headless watcher (`astiop watch run`) is started again when it ends, and
said in the server's log, until the server stops it."""

from __future__ import annotations

import logging
import subprocess
import sys
import time

from astiop.cli import serve_watcher
from astiop.cli.serve_watcher import Watcher


def _until(predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.02)
    return bool(predicate())


def test_a_watcher_that_ends_is_said_and_started_again_until_the_server_stops(monkeypatch, caplog):
    monkeypatch.setattr(serve_watcher, "FIRST_PAUSE_S", 0.05)
    started: list[subprocess.Popen] = []

    def start() -> subprocess.Popen:
        code = "raise SystemExit(3)" if len(started) < 2 else "import time; time.sleep(60)"
        started.append(subprocess.Popen([sys.executable, "-c", code]))
        return started[-1]

    watcher = Watcher(start, lambda p: (p.terminate(), p.wait(10)))
    with caplog.at_level(logging.WARNING, logger="astiop.serve"):
        watcher.start()
        assert _until(lambda: len(started) == 3, 30)
        watcher.close()
    assert watcher.restarts == 2
    assert started[-1].poll() is not None  # the last one, still running, ended by the server
    ended = [r.getMessage() for r in caplog.records if "watch run ended" in r.getMessage()]
    assert len(ended) == 2 and ended[0].startswith("watch run ended (exit code 3)")
