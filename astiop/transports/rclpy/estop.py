"""The rclpy transport's E-STOP: in-flight work ended, a zero Twist now and a burst of them, /stop
called (or, without one, every navigation goal cancelled), and its release."""

from __future__ import annotations

import threading
import time

from astiop.ros2.render import zero_twist
from astiop.ros2.validation import CANCEL_SUFFIX
from astiop.transports.base import BackendError
from astiop.transports.event_log import EstopWork, EventLog
from astiop.transports.inflight import InFlight
from astiop.transports.live_catalog import (
    CANCEL_GOAL,
    NAVIGATE,
    RELEASE,
    LiveGraph,
    navigation_actions,
    stop_service_type,
)
from astiop.transports.rclpy.empty_calls import EmptyCalls
from astiop.transports.rclpy.lock_hold import LockHold
from astiop.transports.rclpy.node import RosProcess
from astiop.transports.rclpy.teleop import TELEOP_HZ, RclpyTeleop

ESTOP_BURST_S = 1.0


class RclpyEstop:
    """The E-STOP in process: it owns its empty service calls, the robot's lock input held
    while it holds, and what it started in the background; the zero Twists go out through
    teleop's publisher."""

    def __init__(
        self,
        proc: RosProcess,
        live: LiveGraph,
        inflight: InFlight,
        events: EventLog,
        timeout_s: float,
        teleop: RclpyTeleop,
        closed: threading.Event,
    ):
        self.proc = proc
        self.live = live
        self.inflight = inflight
        self.events = events
        self.timeout_s = timeout_s
        self.teleop = teleop
        self._closed = closed
        self.work = EstopWork(events)
        self._calls = EmptyCalls(proc, events, timeout_s)
        self._lock_hold = LockHold(proc, lambda: live.name("estop_lock"), events)

    def estop(self) -> list[str]:
        """Everything in flight ended first (timed publishes, goals, teleop), then the zero Twist
        now and /stop called, neither waiting on the other; failures that come later arrive as
        events (`settle`)."""
        failures = self.inflight.stop_all()
        self._lock_hold.hold()  # the robot's own lock input, where it has one
        self.work.begin()
        try:
            self.teleop.zero_now()  # matched already in a running console
            self.work.start(self._zero_burst, "estop-zero")
        except Exception as exc:  # noqa: BLE001 - /stop and the cancels go out regardless
            failures.append(f"{exc}: no zero Twist was sent")
        # The graph this process holds may be partial (a new process's E-STOP does not wait
        # for it): a stop service it shows is called; one it does not show is still tried, and
        # only a robot seen without it has none (said, not failed). Then every NavigateToPose
        # goal on the robot is cancelled, another client's too (a TurtleBot3 has no /stop).
        stop = self.live.name("stop")
        stop_type = stop_service_type(self.live.catalog)
        held = self._still_held
        if stop:
            self.work.start(lambda: self._calls.call(stop, stop_type, "E-STOP", held), "estop-stop")
        else:
            name = self.live.fixed.namespace + "/stop"
            self.work.start(
                lambda: self._calls.call_if_served(
                    name, stop_type, "E-STOP", self._base_seen, held
                ),
                "estop-stop",
            )
            actions = navigation_actions(self.live.catalog, self.live.fixed.namespace) or [
                self.live.fixed.namespace + NAVIGATE
            ]
            for action in actions:
                self.work.start(lambda a=action: self._cancel_every_goal(a), "estop-cancel")
        self.work.said(failures)
        return failures

    def warm(self) -> None:
        """The velocity publisher made in the background, as soon as the base is discovered."""

        def publisher() -> None:
            deadline = time.monotonic() + 60.0
            while not self._closed.is_set() and time.monotonic() < deadline:
                try:
                    self.teleop.publisher()
                    return
                except Exception:  # noqa: BLE001 - the base not discovered yet
                    time.sleep(0.2)

        threading.Thread(target=publisher, name="estop-warm", daemon=True).start()

    def _still_held(self) -> bool:
        """The E-STOP still holds (a release made since must not be undone by its late steps)."""
        return self.inflight.held

    def _cancel_every_goal(self, action: str) -> None:
        """A CancelGoal with a zero goal id and a zero stamp cancels every goal of the action
        server (ros2/rcl_interfaces action_msgs/srv/CancelGoal.srv, humble and jazzy)."""
        name, what = f"{action}{CANCEL_SUFFIX}", "E-STOP cancel"
        if action in self.live.catalog.actions:
            self._calls.call(name, CANCEL_GOAL, what)
        else:  # not on the graph this process holds (yet)
            self._calls.call_if_served(name, CANCEL_GOAL, what, self._base_seen)

    def _base_seen(self) -> bool:
        """The robot's base is on the graph: its velocity command has a subscriber."""
        velocity = self.live.name("velocity_command", "/cmd_vel")
        return bool(self.proc.node.get_subscriptions_info_by_topic(velocity))

    def _zero_burst(self) -> None:
        """A zero Twist at 10 Hz for a second from when the base listens (in a new process,
        discovery may take a moment: the first one may have found no one)."""
        try:
            deadline = time.monotonic() + self.timeout_s
            while True:
                try:
                    pub, _cls, _type = self.teleop.publisher()
                    break
                except BackendError:  # not discovered yet
                    if time.monotonic() > deadline:
                        velocity = self.live.name("velocity_command", "/cmd_vel")
                        raise BackendError(
                            f"no {velocity} on the robot's graph in {self.timeout_s:g} s"
                        ) from None
                    time.sleep(0.01)
            while pub.get_subscription_count() < 1:
                if time.monotonic() > deadline:
                    raise BackendError(
                        f"nothing subscribed to {pub.topic_name} in {self.timeout_s:g} s"
                    )
                time.sleep(0.01)
            end = time.monotonic() + ESTOP_BURST_S
            while time.monotonic() < end and self.inflight.held and not self._closed.is_set():
                self.teleop.send_twist(zero_twist())
                time.sleep(1.0 / TELEOP_HZ)
        except Exception as exc:  # noqa: BLE001 - said, never raised: /stop goes on
            self.events.add("estop", "error", f"E-STOP zero Twist: {exc}")

    def settle(self, timeout_s: float) -> list[str]:
        # /stop waits for its server, then for the answer: each may take the timeout (the
        # burst ends sooner: its timeout and a second)
        return self.work.settle(2 * timeout_s)

    def release(self, *, robot: bool = True) -> list[str]:
        self.inflight.release()
        self._lock_hold.let_go()
        name = self.live.name("release", RELEASE)  # under the robot's namespace
        spec = self.live.catalog.services.get(name)
        if spec is None or not robot:
            return []
        seq = self.events.seq  # a robot that latches its own stop lets go too
        self._calls.call(name, spec.type, "release")
        return [e.message for e in self.events.since(seq) if e.kind == "estop"]

    def close(self) -> None:
        self._lock_hold.stop()
