"""Live state from a real robot: one long-lived `ros2 topic echo` per topic.

Each stream is read as YAML documents separated by `---` (ros2 topic echo's own separator),
never a process per sample; a stream that dies is restarted with back-off and said so.
"""

from __future__ import annotations

import re
import subprocess
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import yaml

from astiop.transports.ros2cli import process as ros2_process

try:
    _Loader = yaml.CSafeLoader
except AttributeError:  # pragma: no cover - PyYAML without libyaml
    _Loader = yaml.SafeLoader

# Lines ros2 prints around the YAML (QoS warnings, lost messages, waiting): not data.
_NOISE = re.compile(
    r"^(WARNING|WARN|\[WARN\]|\[INFO\]|\[ERROR\]|A message was lost|waiting for|"
    r"Could not determine|The message type)",
)
MAX_DOC_LINES = 200_000
BACKOFF_S = (0.5, 1.0, 2.0, 4.0, 8.0)

OnMessage = Callable[[str, dict[str, Any], float], None]
OnEvent = Callable[[str, str, str], None]  # kind, severity, message


def parse_document(lines: list[str]) -> dict[str, Any] | None:
    text = "".join(line for line in lines if not _NOISE.match(line))
    if not text.strip():
        return None
    try:
        doc = yaml.load(text, Loader=_Loader)  # noqa: S506 - a safe loader
    except yaml.YAMLError:
        return None
    return doc if isinstance(doc, dict) else None


class TopicStream:
    def __init__(
        self,
        executable: str,
        name: str,
        type_: str,
        on_message: OnMessage,
        on_event: OnEvent,
        extra: tuple[str, ...] = (),
    ):
        self.executable = executable
        self.name = name
        self.type = type_
        self.extra = extra
        self.on_message = on_message
        self.on_event = on_event
        self.count = 0
        self.received: deque[float] = deque(maxlen=200)  # monotonic receive times
        self.restarts = 0
        self._stop = threading.Event()
        self._proc: subprocess.Popen[str] | None = None
        self._thread = threading.Thread(target=self._loop, name=f"echo{name}", daemon=True)

    def start(self) -> TopicStream:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        proc = self._proc
        if proc is not None:
            ros2_process.stop(proc, grace_s=1.0)
        self._thread.join(3.0)

    def _loop(self) -> None:
        failures = 0
        while not self._stop.is_set():
            argv = ["topic", "echo", self.name, self.type, *self.extra]
            started = time.monotonic()
            try:
                proc = self._proc = ros2_process.spawn(self.executable, argv)
            except Exception as exc:  # noqa: BLE001 - reported, then retried
                self.on_event("stream", "error", f"cannot start echo of {self.name}: {exc}")
            else:
                self._read(proc)
                rc = proc.wait()
                if self._stop.is_set():
                    return
                err = (proc.stderr.read() if proc.stderr else "").strip().splitlines()
                why = err[-1][:200] if err else f"exit status {rc}"
                self.on_event("stream", "warning", f"echo of {self.name} stopped ({why})")
            if time.monotonic() - started > 30:
                failures = 0  # it ran well for a while: start the back-off again
            delay = BACKOFF_S[min(failures, len(BACKOFF_S) - 1)]
            failures += 1
            self.restarts += 1
            if self._stop.wait(delay):
                return

    def _read(self, proc: subprocess.Popen[str]) -> None:
        lines: list[str] = []
        assert proc.stdout is not None  # spawn() pipes it
        for line in proc.stdout:
            if line.rstrip("\n") == "---":
                doc = parse_document(lines)
                lines = []
                if doc is not None:
                    now = time.monotonic()
                    self.count += 1
                    self.received.append(now)
                    self.on_message(self.name, doc, now)
            elif len(lines) < MAX_DOC_LINES:
                lines.append(line)
            if self._stop.is_set():
                return

    def rate(self, now: float, window_s: float = 2.0) -> float:
        times = [t for t in self.received if now - t <= window_s]
        if len(times) < 2:
            return 0.0
        return (len(times) - 1) / (times[-1] - times[0]) if times[-1] > times[0] else 0.0

    def age(self, now: float) -> float:
        return now - self.received[-1] if self.received else float("inf")
