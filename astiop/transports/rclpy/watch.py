"""The robot's state topics by subscription: the latest message of each, kept serialized as it
came (a 50 Hz /odom costs a copy, not a Python object), deserialized and decoded to a dict only
when read; its receive times give rates and ages. rclpy's raw subscriptions and
rclpy.serialization are in Humble too (node.py create_subscription `raw`, serialization.py).

A state topic's watch is polled: the executor never wakes for its messages (a wake of rclpy's
wait-set executor, the only one Humble has, rebuilds its wait set in Python: 2.0 % of a core for
the robot's 27 messages a second, against 0.5 % taken ten times a second). The process's poller
takes what came, with the rmw's receive time of each, as the executor's own _take_subscription
does (humble: rclpy/executors.py; subscription.cpp `take_message` gives `received_timestamp`).
A one-off watch (an echo of an unwatched topic) is handed each message by the executor."""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from rclpy.serialization import deserialize_message
from rclpy.subscription import Subscription

from astiop.ros2.message_objects import MessageTypeError, interface_class, to_dict
from astiop.ros2.transforms import STALE_S, TransformTable
from astiop.transports.rclpy.graph import matched_qos
from astiop.transports.rclpy.node import RosProcess

RATE_WINDOW_S = 2.0
POLLED_DEPTH = 50  # a 50 Hz topic's messages over one second of a stalled poller
NEXT_POLL_S = 0.01  # next_message on a polled watch takes this often, not waiting on the poller


class TopicWatch:
    """One subscription, its latest message and when messages came (time.monotonic())."""

    def __init__(
        self,
        proc: RosProcess,
        name: str,
        type_: str,
        on_message: Callable[[str, Any], None] | None = None,
        polled: bool = False,
    ):
        self.name, self.type, self.polled = name, type_, polled
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
        self._take_lock = threading.Lock()  # the poller or a reader
        self._sub: Subscription | None
        if polled:
            qos = matched_qos(proc, name, POLLED_DEPTH)
            self._sub = proc.node.create_subscription(
                self.cls, name, self._receive, qos, raw=True, callback_group=proc.polled_group
            )
            proc.poll(self)
        else:
            qos = matched_qos(proc, name)
            self._sub = proc.node.create_subscription(self.cls, name, self._receive, qos, raw=True)

    def _receive(self, raw: bytes, at: float | None = None) -> None:
        with self._lock:
            self._raw, self._object, self._decoded = raw, None, None
            self._times.append(time.monotonic() if at is None else at)
            self.count += 1
            self._arrived.notify_all()
        if self._on_message is not None:
            self._on_message(self.name, self.latest_object())

    def take(self) -> None:
        """Take the messages that came since the last take (a polled watch), each at its
        receive time."""
        with self._take_lock:  # received in order, by one taker at a time
            if self._sub is None:
                return
            with self._sub.handle:
                taken = []
                while (got := self._sub.handle.take_message(self.cls, True)) is not None:
                    taken.append(got)
            now = time.monotonic()
            offset = now - time.time()  # the rmw's stamps are system time
            for raw, info in taken:
                ns = info.get("received_timestamp", 0)
                self._receive(raw, min(now, ns * 1e-9 + offset) if ns > 0 else now)

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
        if self.polled:
            self.take()
        with self._lock:
            seen = self.count
        while True:
            if self.polled:
                self.take()
            with self._lock:
                if self.count != seen:
                    return self._object_locked()
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._arrived.wait(min(left, NEXT_POLL_S) if self.polled else left)

    def current(self, max_age_s: float) -> Any:
        """The latest message if it came within `max_age_s` (the topic's last publication), else
        None."""
        if self.polled:
            self.take()
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
        if self.polled:
            self._proc.unpoll(self)
        with self._take_lock:
            sub, self._sub = self._sub, None
        if sub is not None:
            self._proc.node.destroy_subscription(sub)


def watch(
    proc: RosProcess,
    name: str,
    type_: str,
    on_message: Callable[[str, Any], None] | None = None,
) -> TopicWatch | None:
    """A polled watch on the topic, or None when its type is not importable here."""
    try:
        return TopicWatch(proc, name, type_, on_message, polled=True)
    except MessageTypeError:
        return None


def image_watch(proc: RosProcess, name: str, type_: str) -> TopicWatch | None:
    """A camera's watch, handed each frame by the executor (a few a second): the last frame
    kept serialized, depth 10 (a polled watch's 50 frames queued would be megabytes)."""
    try:
        return TopicWatch(proc, name, type_)
    except MessageTypeError:
        return None


class TransformWatch(TopicWatch):
    """/tf or /tf_static: each message folded into the latest transform per (parent, child) as
    it is taken (one /tf message holds a few of the tree's transforms, each publisher its own);
    `latest()` is the tree so far as a TFMessage. An echo still gets the last message as sent."""

    def __init__(self, proc: RosProcess, name: str, type_: str, static: bool):
        self.table = TransformTable(stale_s=None if static else STALE_S)
        super().__init__(proc, name, type_, polled=True)

    def _receive(self, raw: bytes, at: float | None = None) -> None:
        at = time.monotonic() if at is None else at
        self.table.fold_object(deserialize_message(raw, self.cls), at)
        super()._receive(raw, at)

    def latest(self) -> dict[str, Any] | None:
        return self.table.message(time.monotonic())


def watch_transforms(
    proc: RosProcess, name: str, type_: str, static: bool
) -> TransformWatch | None:
    try:
        return TransformWatch(proc, name, type_, static)
    except MessageTypeError:
        return None
