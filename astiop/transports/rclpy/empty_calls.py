"""Services the E-STOP and its release call with an empty request (the robot's stop, its
release, every goal's cancel): each failure said as an event, never raised, so one that does
not answer never holds up the others."""

from __future__ import annotations

import time
from collections.abc import Callable

from astiop.ros2.message_objects import interface_class
from astiop.transports.event_log import EventLog
from astiop.transports.rclpy.node import RosProcess

ABSENT_S = 2.0  # a robot seen this long without the service has none


class EmptyCalls:
    def __init__(self, proc: RosProcess, events: EventLog, timeout_s: float):
        self.proc, self.events, self.timeout_s = proc, events, timeout_s

    def call(
        self, name: str, type_: str, what: str, still: Callable[[], bool] | None = None
    ) -> None:
        """Wait for the server, call, wait for the answer: each up to the timeout. `still`:
        asked right before the call goes out (an E-STOP released meanwhile sends no /stop)."""
        try:
            client = self.proc.client(interface_class(type_), name)
            if not client.wait_for_service(timeout_sec=self.timeout_s):
                self._unanswered(name, what)
                return
            if still is not None and not still():
                self.events.add("estop", "info", f"{what}: released meanwhile, {name} not called")
                return
            request = client.srv_type.Request()
            self.proc.wait(client.call_async(request), self.timeout_s, f"{what} {name}")
        except Exception as exc:  # noqa: BLE001 - said, never raised: the stop goes on
            self.events.add("estop", "error", f"{what} {name}: {exc}")

    def call_if_served(
        self,
        name: str,
        type_: str,
        what: str,
        robot_seen: Callable[[], bool],
        still: Callable[[], bool] | None = None,
    ) -> None:
        """In a process that did not read the graph: called once served; a robot seen
        (`robot_seen`) without it for ABSENT_S has none: said, not a failure (a TurtleBot3 has no
        /stop; its goals are cancelled instead)."""
        try:
            client = self.proc.client(interface_class(type_), name)
        except Exception as exc:  # noqa: BLE001
            self.events.add("estop", "error", f"{what} {name}: {exc}")
            return
        deadline, seen = time.monotonic() + self.timeout_s, None
        while not client.wait_for_service(timeout_sec=0.2):
            now = time.monotonic()
            if robot_seen():
                seen = seen or now
                if now - seen > ABSENT_S:
                    self.events.add("estop", "info", f"{what}: the robot serves no {name}")
                    return
            if now > deadline:
                self._unanswered(name, what)
                return
        self.call(name, type_, what, still)

    def _unanswered(self, name: str, what: str) -> None:
        self.events.add("estop", "error", f"{what}: no {name} answered within {self.timeout_s:g} s")
