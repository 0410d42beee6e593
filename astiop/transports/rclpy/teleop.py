"""The rclpy transport's teleop: the velocity publisher, the held velocity repeated at 10 Hz
until its keys lapse, and a zero Twist at once."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from rclpy.publisher import Publisher

from astiop.ros2.message_objects import interface_class, to_message
from astiop.ros2.render import velocity_message, zero_twist
from astiop.transports.base import BackendError
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import InFlight, Job
from astiop.transports.live_catalog import LiveGraph
from astiop.transports.rclpy.node import RosProcess

TELEOP_HZ = 10.0
LAPSE_S = 0.5

CmdVel = tuple[Publisher, Any, str]  # the publisher, its message class, its type


class RclpyTeleop:
    """The robot's velocity publisher (made once, on first use), and the velocity teleop holds:
    a job of `inflight` while held (the E-STOP ends it), repeated by `loop` until it lapses.
    `want(name)` keeps the robot's odometry watched while this process drives."""

    def __init__(
        self,
        proc: RosProcess,
        live: LiveGraph,
        inflight: InFlight,
        events: EventLog,
        closed: threading.Event,
        want: Callable[[str], None],
    ):
        self.proc = proc
        self.live = live
        self.inflight = inflight
        self.events = events
        self._closed = closed
        self._want = want
        self._lock = threading.Lock()
        self._holding = threading.Event()  # a velocity is held: the loop runs
        self._cmd_vel: CmdVel | None = None
        self._hold: dict | None = None
        self._hold_until = 0.0
        self._job: Job | None = None  # while teleop holds a velocity

    def publisher(self) -> CmdVel:
        with self._lock:
            if self._cmd_vel is None:
                type_ = self._cmd_vel_type()
                cls = interface_class(type_)
                name = self.live.name("velocity_command", "/cmd_vel")
                self._cmd_vel = (self.proc.node.create_publisher(cls, name, 10), cls, type_)
            return self._cmd_vel

    def _cmd_vel_type(self) -> str:
        name = self.live.name("velocity_command", "/cmd_vel")
        spec = self.live.catalog.topics.get(name)
        if spec is not None:
            return spec.type
        # a process that did not wait for discovery (astiop estop): the base's subscription
        infos = self.proc.node.get_subscriptions_info_by_topic(name)
        if infos:
            return infos[0].topic_type
        raise BackendError(f"the robot has no {name}")

    def send_twist(self, twist: dict) -> None:
        pub, cls, type_ = self.publisher()
        pub.publish(self.stamped(cls, velocity_message(type_, twist)))

    def stamped(self, cls: Any, message: dict) -> Any:
        """The message object, a TwistStamped's header stamped now by this node's clock (what
        `header: auto` asks of ros2topic's pub)."""
        msg = to_message(cls, message)
        if hasattr(msg, "header"):
            msg.header.stamp = self.proc.node.get_clock().now().to_msg()
        return msg

    def drive(self, twist: dict) -> None:
        with self._lock:
            if self._job is None:  # refused while the E-STOP holds
                self._job = self.inflight.start("teleop", self._drop_hold)
            job = self._job
            self._hold, self._hold_until = twist, time.monotonic() + LAPSE_S
            self._holding.set()
        with job.sending():
            self.send_twist(twist)  # now, not at the next tick
        self._want(self.live.name("odometry"))  # the velocity it makes, after it is sent

    def replaced(self) -> None:
        """A command publishes on the velocity topic: what teleop held is repeated no more."""
        with self._lock:
            self._hold = None

    def _drop_hold(self) -> None:
        with self._lock:
            self._hold, self._job = None, None

    def loop(self) -> None:
        """Repeat the held velocity at 10 Hz; when the keys stop, one zero Twist. Asleep while
        nothing is held (no wake-up ten times a second for nothing)."""
        while self._holding.wait() and not self._closed.wait(1.0 / TELEOP_HZ):
            with self._lock:
                twist, until, job = self._hold, self._hold_until, self._job
                lapsed = twist is not None and time.monotonic() > until
                if lapsed:
                    self._hold, self._job = None, None
                if self._hold is None:
                    self._holding.clear()  # drive() sets it again, under this lock
            try:
                if lapsed:
                    self.send_twist(zero_twist())
                elif twist is not None and job is not None:
                    with job.sending():
                        self.send_twist(twist)
            except Exception as exc:  # noqa: BLE001
                if job is None or not job.ended_by_estop:  # else: its own zero Twists follow
                    self.events.add("teleop", "error", f"velocity command: {exc}")
            finally:
                if lapsed and job is not None:
                    job.done()

    def zero_now(self) -> None:
        if self.live.name("velocity_command"):
            self.send_twist(zero_twist())

    def close(self) -> None:
        """The loop woken to see the process closed; the publisher destroyed."""
        self._holding.set()
        with self._lock:
            cmd_vel, self._cmd_vel = self._cmd_vel, None
        if cmd_vel is not None:
            self.proc.node.destroy_publisher(cmd_vel[0])
