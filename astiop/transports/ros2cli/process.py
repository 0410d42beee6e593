"""Running the `ros2` executable: argument lists (never a shell), output kept as it streams,
and stopped the way an operator's Ctrl-C stops it (SIGINT, so the client cancels what it
started), then SIGTERM, then SIGKILL.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from astiop.transports.errors import BackendError
from astiop.transports.inflight import Job

MAX_OUTPUT = 4_000_000  # characters kept per stream of one call


@dataclass
class Run:
    argv: list[str]
    stdout: list[str] = field(default_factory=list)
    stderr: list[str] = field(default_factory=list)
    returncode: int | None = None
    stopped: bool = False  # we stopped it (bound reached or asked to)

    @property
    def out(self) -> str:
        return "".join(self.stdout)

    @property
    def err(self) -> str:
        return "".join(self.stderr)


class RunRos2(Protocol):
    """`ros2 ARGV` run as `run` runs it, the executable and the current job given (the
    backend's `_run`): what the transport's helpers are handed."""

    def __call__(
        self,
        argv: list[str],
        timeout: float,
        *,
        until: Callable[[str], bool] | None = None,
        cancel: threading.Event | None = None,
        cancellable: Callable[[str], bool] | None = None,
    ) -> Run: ...


def spawn(executable: str, argv: list[str], *, stdin: bool = False) -> subprocess.Popen:
    try:
        return subprocess.Popen(
            [executable, *argv],
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
            start_new_session=True,  # our signals only; a terminal's Ctrl-C is ours to pass on
        )
    except OSError as exc:
        raise BackendError(f"cannot run {executable}: {exc}") from None


def stop(proc: subprocess.Popen, grace_s: float = 3.0) -> None:
    """SIGINT, then SIGTERM, then SIGKILL; each given a bounded time."""
    for sig, wait in ((signal.SIGINT, grace_s), (signal.SIGTERM, 1.0), (signal.SIGKILL, 1.0)):
        if proc.poll() is not None:
            return
        try:
            os.killpg(proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            return
        try:
            proc.wait(wait)
            return
        except subprocess.TimeoutExpired:
            continue


def kill(proc: subprocess.Popen) -> None:
    """At once, no grace: an E-STOP ending a publisher (it has nothing to cancel)."""
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)


def spawn_owned(
    executable: str,
    argv: list[str],
    job: Job | None,
    end: Callable[[subprocess.Popen], None] = kill,
) -> subprocess.Popen:
    """Spawn as part of `job`: not at all if the E-STOP already ended it, and ended by it with
    `end` (killed at once, by default)."""
    if job is None:
        return spawn(executable, argv)
    with job.sending():
        proc = spawn(executable, argv)
        job.on_estop(lambda: end(proc))
    return proc


def _pump(stream, sink: list[str], on_line: Callable[[str], None] | None) -> None:
    size = 0
    for line in stream:
        if size < MAX_OUTPUT:
            sink.append(line)
            size += len(line)
        if on_line is not None:
            on_line(line)
    stream.close()


def run(
    executable: str,
    argv: list[str],
    timeout: float,
    *,
    until: Callable[[str], bool] | None = None,
    grace_s: float = 3.0,
    job: Job | None = None,
    cancel: threading.Event | None = None,
    cancellable: Callable[[str], bool] | None = None,
) -> Run:
    """Run to completion within `timeout`, or stop it there, or as soon as `until(stdout)` or
    `cancel` is set (while `cancellable(stdout)` holds, if given); as part of `job`, the E-STOP
    kills it.

    The output printed before a stop is kept.
    """
    result = Run(argv)
    proc = spawn_owned(executable, argv, job)
    done = threading.Event()

    def on_line(_line: str) -> None:
        if until is not None and until(result.out):
            done.set()

    pumps = [
        threading.Thread(target=_pump, args=(proc.stdout, result.stdout, on_line), daemon=True),
        threading.Thread(target=_pump, args=(proc.stderr, result.stderr, None), daemon=True),
    ]
    for t in pumps:
        t.start()
    deadline = time.monotonic() + timeout
    try:
        while proc.poll() is None and not done.is_set():
            cancelled = cancel is not None and cancel.is_set()
            if cancelled and cancellable is not None and not cancellable(result.out):
                cancelled = False  # e.g. a request already sent: it runs to its answer
            if time.monotonic() >= deadline or cancelled:
                break
            done.wait(0.02)
        if proc.poll() is None:
            result.stopped = True
            stop(proc, grace_s)
    except BaseException:  # KeyboardInterrupt: pass the operator's Ctrl-C on to ros2
        stop(proc, grace_s)
        raise
    for t in pumps:
        t.join(2.0)
    result.returncode = proc.poll()
    return result
