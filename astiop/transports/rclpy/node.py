"""One rclpy context per process, with one node, spun by its executor on a thread of its own.

Every rclpy backend in the process (the console's, a test's, `astiop estop`'s) shares it; it
shuts down at exit. Only API that Humble's rclpy has (rclpy's humble branch: __init__.py
`init(context=, domain_id=)`, executors.py `spin_once`/`wake`/`shutdown`, node.py's graph calls),
and the wait-set executor on every distro, Humble's only one: the state topics' messages do not
wake it, a poller takes them (watch.py). Jazzy's events executor is not used: it runs every
subscription, polled or not, and costs more than the poller (0.64 against 0.49 % of a core).
"""

from __future__ import annotations

import atexit
import contextlib
import os
import threading
import time
from typing import Any

import rclpy
from rclpy.callback_groups import CallbackGroup
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from astiop.native_stdout import native_output_to_stderr

_lock = threading.Lock()
# Each timeout is a wake-up for nothing (measured idle: 0.45 % of a core at 0.1 s with the
# wait-set executor, 0.04 % at 1 s); what the executor must see wakes it (humble: node.py
# _wake_executor on each entity made or destroyed; close() wakes it).
NODE_PREFIX = "astiop_"  # each astiop process's node: astiop_<pid>
SPIN_TIMEOUT_S = 1.0
POLL_S = 0.1  # the state topics' messages are taken ten times a second
ASK_AGAIN_S = 2.0  # a read service unanswered this long is asked again
_shared: RosProcess | None = None


class RosTimeout(Exception):
    pass


class Polled(CallbackGroup):
    """A group the wait-set executor never waits on: it waits only on entities whose group can
    execute (humble: executors.py _wait_for_ready_callbacks, `filter(self.can_execute, ...)`)."""

    def can_execute(self, entity) -> bool:
        return False

    def beginning_execution(self, entity) -> bool:
        return False

    def ending_execution(self, entity) -> None:
        pass


class RosProcess:
    def __init__(self) -> None:
        native_output_to_stderr()
        self.context = rclpy.Context()
        # No signal handlers on a non-default context. No log lines on stderr: that is the
        # console's screen (rcl's own warnings, such as ROS_LOCALHOST_ONLY's, included).
        rclpy.init(args=["--ros-args", "--disable-stdout-logs"], context=self.context)
        # no parameter services: a console has no parameters to offer the robot's graph
        self.node = Node(
            f"{NODE_PREFIX}{os.getpid()}", context=self.context, start_parameter_services=False
        )
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.polled_group = Polled()
        self._polled: tuple[Any, ...] = ()  # the watches the poller takes for
        self._poller: threading.Thread | None = None
        self._clients: dict[tuple[str, Any], Any] = {}  # (service, type) -> its client
        self._clients_lock = threading.Lock()
        self._poll_lock = threading.Lock()  # the polled watches and the poller
        self._halt = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="rclpy", daemon=True)
        self._thread.start()

    @property
    def domain_id(self) -> int:
        return self.context.get_domain_id()

    def _spin(self) -> None:
        while not self._halt.is_set():
            try:
                self.executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
            except Exception:  # noqa: BLE001 - a callback's failure must not stop the robot's state
                if not self.context.ok():
                    return

    def poll(self, watch: Any) -> None:
        """Have the poller take `watch`'s messages (a TopicWatch made with polled=True)."""
        with self._poll_lock:
            self._polled = (*self._polled, watch)
            if self._poller is None:
                self._poller = threading.Thread(target=self._poll, name="rclpy-poll", daemon=True)
                self._poller.start()

    def unpoll(self, watch: Any) -> None:
        with self._poll_lock:
            self._polled = tuple(w for w in self._polled if w is not watch)

    def _poll(self) -> None:
        """Ends when nothing is left to poll (poll() starts it again)."""
        while not self._halt.wait(POLL_S):
            with self._poll_lock:
                if not self._polled:
                    self._poller = None
                    return
            for w in self._polled:
                try:
                    w.take()
                except Exception:  # noqa: BLE001 - one topic's failure must not stop the others
                    if not self.context.ok():
                        return

    def wait(self, future: Any, timeout: float, what: str) -> Any:
        """The future's result, spun by the executor thread; RosTimeout after `timeout` s."""
        done = threading.Event()
        future.add_done_callback(lambda _f: done.set())
        if not done.wait(timeout):
            future.cancel()
            raise RosTimeout(f"{what}: no answer within {timeout:g} s")
        return future.result()

    def ask(self, client: Any, request: Any, timeout: float, what: str, *, again: bool) -> Any:
        """The answer to one request. A Fast DDS server drops its answer to a client whose
        response reader it has not matched within 100 ms (ros2/rmw_fastrtps#390): on a loaded
        machine a first call can go unanswered. `again`: a read, or a call that only makes the
        robot safer (a stop, a goal's cancel), asked again every ASK_AGAIN_S until `timeout`;
        any other actuation is asked once (it may have been done)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            try:
                return self.wait(
                    client.call_async(request), min(left, ASK_AGAIN_S) if again else left, what
                )
            except RosTimeout:
                if not again or time.monotonic() + 0.05 >= deadline:
                    raise RosTimeout(f"{what}: no answer within {timeout:g} s") from None

    def client(self, srv_type: Any, name: str) -> Any:
        """One client per service, kept: a new one is not matched at once, and a Fast DDS service
        waits for a new client's response reader before it answers (up to 100 ms:
        ros2/rmw_fastrtps#390, #704); measured ~85 ms on one call in five with a new client."""
        with self._clients_lock:
            client = self._clients.get((name, srv_type))
            if client is None:
                client = self.node.create_client(srv_type, name)
                self._clients[(name, srv_type)] = client
            return client

    def call(self, srv_type: Any, name: str, request: Any, timeout: float) -> Any:
        """One service call: wait for the server, ask, wait for the answer; RosTimeout when
        nobody serves `name` or answers within `timeout`."""
        client = self.client(srv_type, name)
        if not client.wait_for_service(timeout_sec=timeout):
            raise RosTimeout(f"{name} is not served")
        return self.wait(client.call_async(request), timeout, name)

    def close(self) -> None:
        self._halt.set()
        with contextlib.suppress(Exception):
            self.executor.wake()
        self._thread.join(2.0)
        if (poller := self._poller) is not None:
            poller.join(2.0)
        with contextlib.suppress(Exception):
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        if self.context.ok():
            with contextlib.suppress(Exception):
                rclpy.shutdown(context=self.context)


def ros_process() -> RosProcess:
    """The process's rclpy context and node, started on first use."""
    global _shared
    with _lock:
        if _shared is None:
            _shared = RosProcess()
            atexit.register(_close)
        return _shared


def _close() -> None:
    global _shared
    with _lock:
        proc, _shared = _shared, None
    if proc is not None:
        proc.close()


def close_shared(timeout_s: float) -> bool:
    """Close the process's rclpy node and context now, waiting at most `timeout_s` (False: it
    did not end in time): its peers forget it at once, not when its DDS lease runs out (Fast
    DDS: 20 s), as they would after an exit with no teardown."""
    ender = threading.Thread(target=_close, name="astiop-rclpy-close", daemon=True)
    ender.start()
    ender.join(timeout_s)
    return not ender.is_alive()
