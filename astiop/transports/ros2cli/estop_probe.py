"""An E-STOP from a process that did not read the graph (`astiop estop`), through `ros2`: its
/stop call goes out at once, and meanwhile the robot's services are listed, hidden ones too
(`ros2 service list -t --include-hidden-services`: an action's cancel_goal is hidden), until the
robot shows. Every goal of its NavigateToPose server is cancelled once listed. A listing cannot
say whether /stop is served: rmw lists a service by its clients too, and the /stop call's own
client is one. So a robot listed while the /stop call still waits, ABSENT_S on, has none (a
TurtleBot3 under Nav2): that call is ended, if it still waits for its server (a request sent is
a slow but real /stop: it runs to its answer), and that is said, not failed, as the rclpy
transport does it (rclpy/empty_calls.py; the CLI's call pays its start-up and a discovery)."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable

from astiop.ros2.validation import CANCEL_SUFFIX
from astiop.transports.live_catalog import CANCEL_GOAL, NAVIGATE

ABSENT_S = 3.0  # a robot listed this long while /stop is not answered has none
_LISTED = re.compile(r"^(?P<name>/\S*)\s+\[(?P<type>[^\]]+)\]\s*$")


class StopProbe:
    def __init__(
        self,
        run: Callable,  # (argv, timeout) -> ros2_process.Run
        namespace: str,
        timeout_s: float,
        call: Callable[[list[str], str], None],  # a background `ros2` call of the E-STOP's
        stop_answered: threading.Event,  # the /stop call ended
    ):
        self.run = run
        self.stop = namespace + "/stop"
        self.cancel = namespace + NAVIGATE + CANCEL_SUFFIX
        self.timeout_s = timeout_s
        self.call = call
        self.stop_answered = stop_answered
        self.stop_absent = threading.Event()  # set: the pending /stop call is ended

    def _listed(self, timeout: float) -> dict[str, str]:
        argv = ["service", "list", "-t", "--include-hidden-services"]
        out = self.run(argv, max(timeout, 0.1))
        return {
            m["name"]: m["type"].split(",")[0].strip()
            for line in out.out.splitlines()
            if (m := _LISTED.match(line.strip()))
        }

    def probe(self) -> None:
        deadline = time.monotonic() + self.timeout_s
        seen, cancelled = None, False
        while True:
            services = self._listed(deadline - time.monotonic())
            now = time.monotonic()
            if not cancelled and services.get(self.cancel) == CANCEL_GOAL:
                cancelled = True  # a zero goal id and stamp cancel every goal
                self.call(["service", "call", self.cancel, CANCEL_GOAL, "{}"],
                          f"cancel every {self.cancel.rsplit('/_action', 1)[0]} goal")  # fmt: skip
            if self.stop_answered.is_set():
                return
            if self.cancel in services:
                seen = seen or now
                if now - seen > ABSENT_S and cancelled:
                    self.stop_absent.set()  # said by the call, if it ended still waiting
                    return
            if now > deadline:
                return  # the /stop call says why it failed
            if self.stop_answered.wait(0.2):
                return
