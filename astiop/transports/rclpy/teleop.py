"""The rclpy transport's teleop: the velocity publisher, the held velocity repeated at 10 Hz
until its keys lapse, and a zero Twist at once."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any, Protocol

from astiop.ros2.catalog import Catalog
from astiop.ros2.message_objects import interface_class, to_message
from astiop.ros2.render import velocity_message, zero_twist
from astiop.transports.base import BackendError
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import InFlight, Job
from astiop.transports.rclpy.node import RosProcess

TELEOP_HZ = 10.0
LAPSE_S = 0.5


class RclpyTeleopHost(Protocol):
    """What `RclpyTeleop` needs of the backend it is mixed into."""

    catalog: Catalog
    proc: RosProcess
    inflight: InFlight
    events: EventLog
    _lock: threading.Lock
    _closed: threading.Event
    _holding: threading.Event
    _cmd_vel: tuple[Any, Any, str] | None
    _teleop_job: Job | None
    _hold: dict | None
    _hold_until: float

    def _name(self, role: str, default: str = "") -> str: ...

    def _want(self, name: str) -> None: ...


if TYPE_CHECKING:
    _Host = RclpyTeleopHost
else:
    _Host = object


class RclpyTeleop(_Host):
    def _publisher(self) -> tuple[Any, Any, str]:
        with self._lock:
            return self._publisher_locked()

    def _publisher_locked(self) -> tuple[Any, Any, str]:
        if self._cmd_vel is None:
            type_ = self._cmd_vel_type()
            cls = interface_class(type_)
            name = self._name("velocity_command", "/cmd_vel")
            self._cmd_vel = (self.proc.node.create_publisher(cls, name, 10), cls, type_)
        return self._cmd_vel

    def _cmd_vel_type(self) -> str:
        name = self._name("velocity_command", "/cmd_vel")
        spec = self.catalog.topics.get(name)
        if spec is not None:
            return spec.type
        # a process that did not wait for discovery (astiop estop): the base's subscription
        infos = self.proc.node.get_subscriptions_info_by_topic(name)
        if infos:
            return infos[0].topic_type
        raise BackendError(f"the robot has no {name}")

    def _send_twist(self, twist: dict) -> None:
        pub, cls, type_ = self._publisher()
        pub.publish(self._stamped(cls, velocity_message(type_, twist)))

    def _stamped(self, cls: Any, message: dict) -> Any:
        """The message object, a TwistStamped's header stamped now by this node's clock (what
        `header: auto` asks of ros2topic's pub)."""
        msg = to_message(cls, message)
        if hasattr(msg, "header"):
            msg.header.stamp = self.proc.node.get_clock().now().to_msg()
        return msg

    def drive(self, twist: dict) -> None:
        with self._lock:
            if self._teleop_job is None:  # refused while the E-STOP holds
                self._teleop_job = self.inflight.start("teleop", self._drop_hold)
            job = self._teleop_job
            self._hold, self._hold_until = twist, time.monotonic() + LAPSE_S
            self._holding.set()
        with job.sending():
            self._send_twist(twist)  # now, not at the next tick
        self._want(self._name("odometry"))  # the velocity it makes, after it is sent

    def _drop_hold(self) -> None:
        with self._lock:
            self._hold, self._teleop_job = None, None

    def _teleop_loop(self) -> None:
        """Repeat the held velocity at 10 Hz; when the keys stop, one zero Twist. Asleep while
        nothing is held (no wake-up ten times a second for nothing)."""
        while self._holding.wait() and not self._closed.wait(1.0 / TELEOP_HZ):
            with self._lock:
                twist, until, job = self._hold, self._hold_until, self._teleop_job
                lapsed = twist is not None and time.monotonic() > until
                if lapsed:
                    self._hold, self._teleop_job = None, None
                if self._hold is None:
                    self._holding.clear()  # drive() sets it again, under this lock
            try:
                if lapsed:
                    self._send_twist(zero_twist())
                elif twist is not None and job is not None:
                    with job.sending():
                        self._send_twist(twist)
            except Exception as exc:  # noqa: BLE001
                if job is None or not job.ended_by_estop:  # else: its own zero Twists follow
                    self.events.add("teleop", "error", f"velocity command: {exc}")
            finally:
                if lapsed and job is not None:
                    job.done()

    def zero_now(self) -> None:
        if self._name("velocity_command"):
            self._send_twist(zero_twist())
