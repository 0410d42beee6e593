"""The robot's own E-STOP or lock input (the `estop_lock` role: a std_msgs/msg/Bool the base or
its twist_mux listens to), held true while the E-STOP latches and said false on its release.

twist_mux silences every velocity source of a lower priority while a lock is true, and with a
lock `timeout` > 0 it takes a lock whose publisher went silent as engaged (ros-teleop/twist_mux
config/twist_mux_locks.yaml; include/twist_mux/topic_handle.hpp: LockTopicHandle, a Bool on
SystemDefaultsQoS): so it is said again at HOLD_HZ, not once."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from std_msgs.msg import Bool

from astiop.transports.event_log import EventLog
from astiop.transports.rclpy.node import RosProcess

HOLD_HZ = 5.0
RELEASE_REPEATS = 3


class LockHold:
    def __init__(self, proc: RosProcess, name: Callable[[], str], events: EventLog):
        self.proc, self._name, self.events = proc, name, events
        self._pub: Any = None
        self._topic = ""
        self._held = threading.Event()
        self._wake = threading.Event()  # a release ends the wait between two words
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def _publisher(self) -> Any:
        """The lock's publisher, made once its role is known on the robot's graph (None: the
        robot has no such input)."""
        name = self._name()
        if not name:
            return None
        if self._pub is None or self._topic != name:
            self._pub = self.proc.node.create_publisher(Bool, name, 10)
            self._topic = name
        return self._pub

    def hold(self) -> None:
        """True from now on, said HOLD_HZ times a second until `let_go()`."""
        with self._lock:
            self._held.set()
            self._wake.clear()
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._loop, name="estop-lock", daemon=True)
                self._thread.start()

    def let_go(self) -> None:
        with self._lock:
            was = self._held.is_set()
            self._held.clear()
            self._wake.set()
        if was:
            self._say(False, RELEASE_REPEATS)

    def stop(self) -> None:
        """This process is done with the robot: nothing more said (the lock stays as the last
        word left it: a latched robot stays locked)."""
        self._held.clear()
        self._wake.set()

    def _loop(self) -> None:
        while self._held.is_set():
            self._say(True, 1)
            self._wake.wait(1.0 / HOLD_HZ)

    def _say(self, value: bool, times: int) -> bool:
        try:
            pub = self._publisher()
            if pub is None:
                return False
            for _ in range(times):
                pub.publish(Bool(data=value))
            return True
        except Exception as exc:  # noqa: BLE001 - said; the E-STOP's other steps go on
            self.events.add("estop", "error", f"E-STOP lock {self._topic or '?'}: {exc}")
            return False
