"""What every simulated robot served as real ROS 2 nodes shares: its rclpy context, nodes and
executor, a shutdown that lets running goals end first, QoS profiles, stamped messages, the
robot's clock on every header. `serving.py` starts them (and needs no ROS to import).

rclpy API used here is Humble's too (rclpy's humble branch: node.py, executors.py, qos.py).
"""

from __future__ import annotations

import heapq
import itertools
import math
import threading
import time
import traceback
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

from astiop.robot.safety import UNIT_QUATERNION_TOLERANCE

GOAL_ABORT_S = 1.5  # at shutdown: how long running goals have to be aborted
SPIN_S = 0.25  # an idle executor wakes this often to see whether it should stop
MAP_TYPE = "nav_msgs/msg/OccupancyGrid"

try:  # rclpy's jazzy name; humble's: rclpy/rclpy/qos_event.py
    from rclpy.event_handler import PublisherEventCallbacks
except ImportError:  # pragma: no cover - humble
    from rclpy.qos_event import PublisherEventCallbacks

# No QoS event handlers of rclpy's own on a simulated robot's publishers: each is a waitable in
# every executor wait, and with a fleet's hundreds of publishers they cost most of a core.
QUIET_EVENTS = PublisherEventCallbacks(use_default_callbacks=False)

RELIABLE = QoSProfile(depth=10)
LATCHED = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)
QOS = {"": RELIABLE, "sensor_data": qos_profile_sensor_data, "transient_local": LATCHED}


def stamped(message: dict[str, Any], stamp: dict[str, int]) -> dict[str, Any]:
    """Every header in the message stamped with the robot's clock, as a driver stamps it."""
    out = {}
    for key, value in message.items():
        if key == "header" and isinstance(value, dict):
            value = {**value, "stamp": stamp}
        elif isinstance(value, dict):
            value = stamped(value, stamp)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            value = [stamped(v, stamp) for v in value]
        out[key] = value
    return out


def now_stamp(node: Node) -> dict[str, int]:
    now = node.get_clock().now().to_msg()
    return {"sec": now.sec, "nanosec": now.nanosec}


def duration(seconds: float) -> dict[str, int]:
    seconds = max(0.0, min(seconds, 2.0**31 - 1))
    sec = int(seconds)
    return {"sec": sec, "nanosec": int((seconds - sec) * 1e9)}


def goal_refusal(pose: dict[str, Any], frames: tuple[str, ...] = ("", "map")) -> str:
    frame = pose["header"]["frame_id"]
    if frame not in frames:
        return f"goals must be in the map frame, not '{frame}'"
    q = pose["pose"]["orientation"]
    norm = math.hypot(q["x"], q["y"], q["z"], q["w"])
    if not abs(norm - 1.0) <= UNIT_QUATERNION_TOLERANCE:
        return f"the orientation is not a unit quaternion (|q| = {norm:.6g})"
    return ""


class Schedule:
    """Periodic sends (a topic at its rate) on one thread of their own, off every executor: an
    executor woken by a timer rebuilds its wait set over every entity of its nodes (O(entities)
    in Python), and a fleet's hundreds of timers kept its executors busy doing only that."""

    def __init__(self) -> None:
        self._due: list[tuple[float, int, float, Callable[[], None]]] = []  # a heap: soonest first
        self._count = itertools.count()  # ties broken by the order the sends were added
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._halt = threading.Event()
        self._failed: set[int] = set()

    def every(self, period_s: float, send: Callable[[], None]) -> None:
        with self._lock:
            entry = (time.monotonic() + period_s, next(self._count), period_s, send)
            heapq.heappush(self._due, entry)

    def start(self) -> None:
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="publish", daemon=True)
                self._thread.start()

    def stop(self) -> None:
        self._halt.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)

    def _take_due(self, now: float) -> tuple[list[tuple[int, Callable[[], None]]], float]:
        """The sends due now, each put back a period on; when the next one is due."""
        due = []
        with self._lock:
            while self._due and self._due[0][0] <= now:
                at, n, period, send = heapq.heappop(self._due)
                # a late tick is not caught up: the next is a period away
                heapq.heappush(self._due, (at + period if at + period > now else now + period,
                                           n, period, send))  # fmt: skip
                due.append((n, send))
            return due, self._due[0][0] if self._due else now + 0.1

    def _run(self) -> None:
        while not self._halt.is_set():
            due, soonest = self._take_due(time.monotonic())
            for n, send in due:
                try:
                    send()
                except Exception:  # noqa: BLE001 - one topic's failure stops no other topic
                    if self._halt.is_set():
                        return  # a context shut down under it, at the end
                    if n not in self._failed:  # said once per topic, not at its rate
                        self._failed.add(n)
                        traceback.print_exc()
            self._halt.wait(max(soonest - time.monotonic(), 0.0005))


class RobotNodes:
    """A robot's nodes in one rclpy context, spun by one executor until `stop()`. With a
    `parent`, its nodes are made in the parent's context, which the parent ends (a fleet's
    robots in one process, each spun by an executor of its own: one executor's wait set over
    every robot's entities costs O(N²)); `domain_id` puts a context on a domain of its own."""

    def __init__(self, parent: RobotNodes | None = None, domain_id: int | None = None) -> None:
        self.parent = parent
        self.domain_id = domain_id
        self.context = parent.context if parent else rclpy.Context()
        self.nodes: dict[str, Node] = {}
        self._executor: MultiThreadedExecutor | None = None
        self.schedule = parent.schedule if parent else Schedule()  # a fleet's: one thread
        self._stopped = parent._stopped if parent else threading.Event()
        self._goals_running = 0

    def init_context(self) -> None:
        if self.parent is None:  # domain_id: ros2/rclpy humble rclpy/rclpy/__init__.py
            rclpy.init(context=self.context, domain_id=self.domain_id)

    def add_node(self, name: str, key: str = "", **options: Any) -> Node:
        """A node by its full name ("/amcl", "/tb3_1/global_costmap/global_costmap"), kept
        under `key` (default: that name)."""
        ns, _, base = name.rpartition("/")
        node = Node(base, namespace=ns or "/", context=self.context, **options)
        self.nodes[key or name] = node
        return node

    def start_executor(self) -> None:
        self._executor = MultiThreadedExecutor(num_threads=4, context=self.context)
        for node in self.nodes.values():
            self._executor.add_node(node)
        self.schedule.start()

    @property
    def stopping(self) -> bool:
        return self._stopped.is_set() or not self.context.ok()

    def goal_running(self) -> _GoalCount:
        return _GoalCount(self.parent or self)

    def spin(self) -> None:
        """Serve until `stop()` (from a signal handler or another thread); then a little longer,
        so a goal still running is aborted and its client told so before the nodes go."""
        assert self._executor is not None
        while not self._stopped.is_set() and self.context.ok():
            self._executor.spin_once(timeout_sec=SPIN_S)
        deadline = time.monotonic() + GOAL_ABORT_S
        while self._goals_running and time.monotonic() < deadline and self.context.ok():
            self._executor.spin_once(timeout_sec=0.05)
        end = time.monotonic() + 0.2  # the result's response goes out
        while time.monotonic() < end and self.context.ok():
            self._executor.spin_once(timeout_sec=0.05)

    def every(self, period_s: float, send: Callable[[], None]) -> None:
        """`send()` every period_s (wall time) from the schedule's thread, not an executor's."""
        self.schedule.every(period_s, send)

    def stop(self) -> None:
        self._stopped.set()
        if self._executor is not None:
            self._executor.wake()  # now, not at its next timeout

    def close_nodes(self) -> None:
        self.schedule.stop()  # nothing published on a node being destroyed
        if self._executor is not None:
            self._executor.shutdown(timeout_sec=1.0)
        for node in self.nodes.values():
            node.destroy_node()
        if self.parent is None and self.context.ok():
            rclpy.shutdown(context=self.context)


class _GoalCount:
    def __init__(self, robot: RobotNodes):
        self.robot = robot

    def __enter__(self) -> None:
        self.robot._goals_running += 1

    def __exit__(self, *_exc: object) -> None:
        self.robot._goals_running -= 1
