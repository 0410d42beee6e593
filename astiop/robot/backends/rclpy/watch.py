"""The robot's state topics by subscription: the latest message object of each, its receive
times (rates and ages come from them), decoded to a dict only when read."""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from astiop.robot.backends.rclpy.graph import matched_qos
from astiop.robot.backends.rclpy.node import RosProcess
from astiop.ros2.message_objects import MessageTypeError, interface_class, to_dict

RATE_WINDOW_S = 2.0


class TopicWatch:
    """One subscription, its latest message and when messages came (time.monotonic())."""

    def __init__(self, proc: RosProcess, name: str, type_: str, on_message: Callable | None = None):
        self.name, self.type = name, type_
        self.count = 0
        self._lock = threading.Lock()
        self._latest: Any = None
        self._decoded: dict[str, Any] | None = None
        self._times: deque[float] = deque(maxlen=4096)
        self._arrived = threading.Condition(self._lock)
        self._on_message = on_message
        self._proc = proc
        self._sub = proc.node.create_subscription(
            interface_class(type_), name, self._receive, matched_qos(proc, name)
        )

    def _receive(self, msg: Any) -> None:
        now = time.monotonic()
        with self._lock:
            self._latest, self._decoded = msg, None
            self._times.append(now)
            self.count += 1
            self._arrived.notify_all()
        if self._on_message is not None:
            self._on_message(self.name, msg)

    def latest(self) -> dict[str, Any] | None:
        with self._lock:
            if self._latest is not None and self._decoded is None:
                self._decoded = to_dict(self._latest)
            return self._decoded

    def latest_object(self) -> Any:
        with self._lock:
            return self._latest

    def received(self) -> float | None:
        with self._lock:
            return self._times[-1] if self._times else None

    def next_message(self, timeout: float) -> Any:
        """The first message that arrives from now on, or None."""
        deadline = time.monotonic() + timeout
        with self._lock:
            seen = self.count
            while self.count == seen:
                left = deadline - time.monotonic()
                if left <= 0 or not self._arrived.wait(left):
                    return None
            return self._latest

    def rate(self, now: float) -> float:
        with self._lock:
            recent = [t for t in self._times if now - t <= RATE_WINDOW_S]
        if len(recent) < 2:
            return 0.0
        return (len(recent) - 1) / (recent[-1] - recent[0]) if recent[-1] > recent[0] else 0.0

    def age(self, now: float) -> float:
        last = self.received()
        return now - last if last is not None else math.inf

    def close(self) -> None:
        self._proc.node.destroy_subscription(self._sub)


def watch(proc: RosProcess, name: str, type_: str, on_message=None) -> TopicWatch | None:
    """A watch on the topic, or None when its type is not importable here."""
    try:
        return TopicWatch(proc, name, type_, on_message)
    except MessageTypeError:
        return None
