"""The robot's state topics by subscription: the latest message of each, kept serialized as it
came (a 50 Hz /odom costs a copy, not a Python object), deserialized and decoded to a dict only
when read; its receive times give rates and ages. rclpy's raw subscriptions and
rclpy.serialization are in Humble too (node.py create_subscription `raw`, serialization.py)."""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from rclpy.serialization import deserialize_message

from astiop.robot.backends.rclpy.graph import matched_qos
from astiop.robot.backends.rclpy.node import RosProcess
from astiop.ros2.message_objects import MessageTypeError, interface_class, to_dict

RATE_WINDOW_S = 2.0


class TopicWatch:
    """One subscription, its latest message and when messages came (time.monotonic())."""

    def __init__(self, proc: RosProcess, name: str, type_: str, on_message: Callable | None = None):
        self.name, self.type = name, type_
        self.cls = interface_class(type_)
        self.count = 0
        self._lock = threading.Lock()
        self._raw: bytes | None = None
        self._object: Any = None
        self._decoded: dict[str, Any] | None = None
        self._times: deque[float] = deque(maxlen=4096)
        self._arrived = threading.Condition(self._lock)
        self._on_message = on_message
        self._proc = proc
        self._sub = proc.node.create_subscription(
            self.cls, name, self._receive, matched_qos(proc, name), raw=True
        )

    def _receive(self, raw: bytes) -> None:
        now = time.monotonic()
        with self._lock:
            self._raw, self._object, self._decoded = raw, None, None
            self._times.append(now)
            self.count += 1
            self._arrived.notify_all()
        if self._on_message is not None:
            self._on_message(self.name, self.latest_object())

    def latest(self) -> dict[str, Any] | None:
        with self._lock:
            if self._raw is not None and self._decoded is None:
                self._decoded = to_dict(self._object_locked())
            return self._decoded

    def latest_object(self) -> Any:
        with self._lock:
            return self._object_locked()

    def _object_locked(self) -> Any:
        if self._raw is not None and self._object is None:
            self._object = deserialize_message(self._raw, self.cls)
        return self._object

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
            return self._object_locked()

    def current(self, max_age_s: float) -> Any:
        """The latest message if it came within `max_age_s` (the topic's last publication), else
        None."""
        with self._lock:
            fresh = self._times and time.monotonic() - self._times[-1] <= max_age_s
            return self._object_locked() if fresh else None

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
