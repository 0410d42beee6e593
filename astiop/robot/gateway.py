"""The one door to the robot: validate, review for safety, confirm, execute; and its live state.

The E-STOP is latched in the store, so every astiop process on that database refuses actuation
while it holds, and a restart keeps it. It is checked before the confirmation and again right
before anything is sent.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from astiop.robot.camera import CameraReading, read_camera
from astiop.robot.command_journal import CommandJournal
from astiop.robot.estop_latch import ESTOP_REASON, EstopLatch
from astiop.robot.graph_reading import GraphReading
from astiop.robot.latch_watch import LatchWatcher
from astiop.robot.safety import Review, SafetyPolicy
from astiop.robot.station_latch import StationLatch
from astiop.ros2.fleet_names import robot_under
from astiop.ros2.render import STAMPED
from astiop.ros2.validation import Checked, validate
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import TAKE
from astiop.store import Store
from astiop.transports.base import BackendError, Execution, MapGeometry, RobotBackend
from astiop.transports.playback import Playback, PlaysBack
from astiop.transports.state import RobotEvent, RobotState, TopicStat

Confirm = Callable[[Checked], bool]
log = logging.getLogger("astiop.robot")
MAX_STAMP_AGE_S = 86400.0  # a stamp older than a day is on another clock, not a day-old reading


class RobotGateway(EstopLatch, GraphReading):
    def __init__(
        self,
        backend: RobotBackend,
        safety: SafetyPolicy | None = None,
        timeout_s: float = 10.0,
        *,
        store: Store | None = None,
        who: str = "astiop",
        restore_latch: bool = True,
        latch_key: str = "",
    ):
        """`restore_latch=False`: a latched E-STOP is not sent again here (`astiop estop`
        sends it at once itself: twice, every step went out twice)."""
        self.backend = backend
        self.safety = safety or SafetyPolicy()
        if self.safety.where is None:  # a speed or keepout zone acts on where the robot is
            self.safety.where = self._pose_now
        self.timeout_s = timeout_s
        self.store = store
        self.who = who
        self._last_drive: tuple[float, float, float] | None = None
        self._journaled = 0  # the last event kept in the store
        self._store_errors: set[str] = set()
        self._journal_lock = threading.Lock()
        self._latch_lock = threading.Lock()
        self.latch_key = latch_key  # a namespaced robot latches its own E-STOP (a fleet's)
        self.station_latch: StationLatch | None = None  # the latch on the robot's graph
        self._latch_seen = False
        self._latch_seen = self.latched
        self.lease = None  # robot/lease.py: set where the robot is shared (ROS 2)
        # a fleet's robot reached through a whole-domain gateway by its names: its lease, made
        # by this (robot/factory.py) the first time a motion is sent to it
        self.lease_of: Callable[[str], Any] | None = None
        self._leases: dict[str, Any] = {}
        self._leases_lock = threading.Lock()
        self.use_map()
        if restore_latch and self._latch_seen and not backend.e_stopped:
            backend.estop()  # a restart keeps the E-STOP until it is released
        # another process's E-STOP ends what this one has in flight, with no one asking
        self._watcher = (
            LatchWatcher(store, backend.inflight, self.follow_latch).start() if store else None
        )

    @property
    def kind(self) -> str:
        """Which robot: sim, ros2 or replay."""
        return self.backend.name

    @property
    def label(self) -> str:
        """How the robot is named to the operator (its transport, distro and domain)."""
        return self.backend.label or self.backend.name

    # -- live state ------------------------------------------------------------------------
    def start(self) -> None:
        self.backend.start()

    def follow_stations(self, namespace: str) -> None:
        """Follow the E-STOP that every station says on the robot's graph, and say this one's
        (robot/station_latch.py), where the transport can reach the graph."""
        backend = self.backend
        self.station_latch = StationLatch(
            lambda heard: backend.estop_channel(namespace, heard), self.follow_latch
        ).start()

    def take_control(self, force: bool = False) -> str | None:
        """Take the lease of a shared robot (robot/lease.py); why it could not be (None: this
        process controls it, or the robot is this process's own)."""
        if self.lease is None:
            return None
        other = self.lease.take(force)
        if other is None:
            return None
        return f"{self.lease.name} is controlled by {other.words}"

    def let_go_of_control(self) -> None:
        """Give up control of a shared robot (it is free for another operator to take)."""
        if self.lease is not None:
            self.lease.let_go()

    def watch_lightly(self, light: bool) -> None:
        """A fleet's robot other than the current one is watched for its row only."""
        self.backend.watch_lightly(light)

    def close(self) -> None:
        for lease in [self.lease, *self._leases.values()]:
            if lease is not None:
                lease.release()
        if self._watcher is not None:
            self._watcher.close()
        if self.station_latch is not None:
            self.station_latch.close()
        self.backend.close()

    def state(self) -> RobotState:
        latched = self.follow_latch()  # first: the backend may follow another process
        if self.safety.geofence is None or (
            self.store is not None and self.store.map_name != self.profile.map_name
        ):
            self.use_map()  # its /map came in, or its make was recognised on a fuller graph
        return self.backend.state().with_e_stop(latched)

    def _pose_now(self) -> tuple[float, float, float] | None:
        pose = self.backend.state().pose
        return (pose.x, pose.y, pose.theta) if pose is not None else None

    def events_since(self, seq: int) -> list[RobotEvent]:
        """The robot's events after `seq`. Each is kept in the store the first time any reader
        (the console's sampler, a recording, `astiop record`) sees it, as commands are."""
        events = self.backend.events_since(seq)
        if self.store is not None and events:
            with self._journal_lock:
                new = [e for e in events if e.seq > self._journaled]
                if new:
                    self._journaled = new[-1].seq
            if new:
                failed = self.store.keep_robot_events(new, self.latch_key.strip("/"))
                if failed:
                    self._say_store_error(failed)
        return events

    def messages(self, names) -> dict[str, dict]:
        """The latest message per topic, as the robot sent it (for recording)."""
        return self.backend.messages(names)

    def message_times(self, names) -> dict[str, float]:
        return self.backend.message_times(names)

    def topic_stats(self) -> list[TopicStat]:
        return self.backend.topic_stats()

    def camera(self) -> CameraReading:
        """The camera role's latest frame, decoded, or why there is none."""
        return read_camera(self)

    def map_geometry(self) -> MapGeometry:
        return self.backend.map_geometry()

    def wait_until_idle(self, timeout_s: float) -> str | None:
        """Block until the robot has no active goal; how the goal ended, when known."""
        return self.backend.wait_until_idle(timeout_s)

    @property
    def read_only_reason(self) -> str:
        return self.backend.read_only or f"the {self.backend.name} robot is read-only"

    @property
    def playback(self) -> Playback | None:
        """The replay's clock (pause, step, speed), or None on a live robot."""
        return self.backend.playback if isinstance(self.backend, PlaysBack) else None

    # -- commands --------------------------------------------------------------------------
    def review(self, text: str) -> Review:
        checked = validate(text, self.catalog)
        if not checked.valid and (
            checked.reason.startswith("there is no") or " has no parameter " in checked.reason
        ):
            checked = self.checked_once_heard(text, checked)  # it may have appeared since
        if self.safety.geofence is None and checked.valid and checked.kind == "actuate":
            self.use_map()  # the robot's /map may have come in since
            if self.safety.geofence is None:  # a one-shot command: its map read now
                self.backend.read_map(self.timeout_s)
                self.use_map()
        return self.safety.review(checked, self.e_stopped)

    def run(
        self,
        text: str,
        confirm: Confirm | None = None,
        timeout: float | None = None,
        source: str | None = None,
        review: Review | None = None,
    ) -> Execution:
        """Run one command. Nothing reaches the backend unless it is valid, safe and confirmed.
        With a `source` (exec, teleop), a valid command is recorded in the store, whether it
        ran or safety, the E-STOP or the operator held it; text that is not a command is not."""
        journal = CommandJournal(self, source) if source else None
        result = self._run(text, confirm, timeout, review, journal)
        if journal is not None and result.valid:
            journal.finish(result)
        return result

    def record(self, ex: Execution, source: str) -> None:
        CommandJournal(self, source).finish(ex)

    def _say_store_error(self, message: str) -> None:
        """A record the store could not keep: said once per reason (the robot was driven all the
        same; a read-only database still drives it)."""
        if message not in self._store_errors:
            self._store_errors.add(message)
            log.error(message)

    def _run(
        self,
        text: str,
        confirm: Confirm | None,
        timeout: float | None,
        review: Review | None,
        journal: CommandJournal | None = None,
    ) -> Execution:
        t0 = time.perf_counter()
        if review is None or review.checked.text != text:
            review = self.review(text)  # else it was reviewed moments ago (held still rechecked)
        checked = review.checked
        result = Execution(
            text.strip(), checked.valid, checked.reason, checked.kind, notes=list(checked.notes)
        )
        if not self.backend.runs_commands:
            result.reason = self.read_only_reason
            return result
        if not review.allowed:
            result.reason = review.reason
            return result
        if why := self._lease_refusal(checked):
            result.reason = why  # another operator controls this robot
            return result
        if review.needs_confirmation:
            if confirm is None:
                result.reason = "this command moves the robot and needs the operator's confirmation"
                return result
            if not confirm(checked):
                result.reason = "not confirmed by the operator"
                return result
        if checked.kind == "actuate" and self._held_by_estop(checked):
            result.reason = ESTOP_REASON  # pressed while the operator was deciding
            return result
        if journal is not None:
            journal.sent(result)  # before the robot is told: a crash meanwhile leaves its record
        try:
            result.output, result.values = self.backend.execute(checked, timeout or self.timeout_s)
            result.executed = True
            result.provenance = self._provenance(checked)
            self._name_role(checked.command.name, result)
            if VERBS[checked.command.key].means == TAKE:  # one message: its age is known
                self._date_reading(checked.command.name, result)
        except BackendError as exc:
            result.executed = True
            result.error = str(exc)
            result.output = f"error: {exc}\n"
        self._adopt_speed_limits(checked, result)
        result.duration_s = time.perf_counter() - t0
        return result

    def _provenance(self, checked: Checked) -> str:
        cmd = checked.command
        if VERBS[cmd.key].measures:
            return "measured"
        if cmd.verb == "service" and cmd.sub == "call":
            spec = self.catalog.services.get(cmd.name)
            return "accepted" if spec is not None and spec.starts_job else "reported"
        return "commanded" if checked.kind == "actuate" else "reported"

    def _name_role(self, name: str | None, result: Execution) -> None:
        """The role the command's name plays on the robot, and a battery's units: what it read
        is then said as a battery, a pose, whatever the robot calls it."""
        profile = self.profile
        result.role = next((r for r, m in profile.matches.items() if name and m.name == name), "")
        if result.role == "battery":
            result.units = profile.units.battery_percentage
        data = result.values.get("data") if isinstance(result.values, dict) else None
        if result.role == "camera" and isinstance(data, list | tuple | bytes | str):
            # an image is read as what it is, not as its pixels (megabytes kept in the store)
            kept = {k: v for k, v in result.values.items() if k != "data"}
            result.values = {**kept, "data_bytes": len(data)}

    def _date_reading(self, topic: str, result: Execution) -> None:
        """A reading's period and its age by its header stamp, when the robot's clock is known
        here and agrees with the stamp (a stamp on another clock, e.g. sim time, says nothing)."""
        spec = self.catalog.topics.get(topic)
        if spec is not None and spec.rate_hz > 0:
            result.period_s = 1.0 / spec.rate_hz
        header = result.values.get("header") if isinstance(result.values, dict) else None
        stamp = header.get("stamp") if isinstance(header, dict) else None
        now = self.backend.robot_time()
        if now is None or not isinstance(stamp, dict):
            return
        try:
            age = now - (int(stamp["sec"]) + int(stamp["nanosec"]) * 1e-9)
        except (KeyError, TypeError, ValueError):
            return
        if -1.0 <= age <= MAX_STAMP_AGE_S:
            result.age_s = max(age, 0.0)

    def cancel_goals(self) -> None:
        """Cancel the goals this process sent and that run (a mission's cancel on a Nav2 robot,
        whose navigation drives on through a zero velocity)."""
        self.backend.cancel_goals()

    def drive(self, vx: float, vy: float, wz: float) -> Execution:
        """Teleop: the key press is the operator's consent; safety still clamps and holds.
        Each change of velocity is recorded (source teleop), not each repeat of a held key."""
        result = self._drive(vx, vy, wz)
        if (vx, vy, wz) != self._last_drive:
            self._last_drive = (vx, vy, wz)
            self.record(result, "teleop")
        return result

    def _drive(self, vx: float, vy: float, wz: float) -> Execution:
        twist = f"{{linear: {{x: {vx:g}, y: {vy:g}}}, angular: {{z: {wz:g}}}}}"
        name = self.profile.name("velocity_command") or "/cmd_vel"
        spec = self.catalog.topics.get(name)
        type_ = spec.type if spec else "geometry_msgs/msg/Twist"
        values = f"{{twist: {twist}}}" if type_ == STAMPED else twist
        text = f'ros2 topic pub --once {name} {type_} "{values}"'
        review = self.review(text)
        result = Execution(text, review.checked.valid, review.reason, "actuate")
        if not self.backend.drives:
            result.reason = self.read_only_reason
            return result
        if not review.allowed:
            return result
        if why := self._lease_refusal(review.checked):
            result.reason = why
            return result
        if self._held_by_estop(review.checked):
            result.reason = ESTOP_REASON
            return result
        result.notes = list(review.checked.notes)
        try:
            message = review.checked.message
            self.backend.drive(message["twist"] if type_ == STAMPED else message)
            result.executed = True
            result.values = review.checked.message
        except BackendError as exc:
            result.error = str(exc)
        return result

    def _other_robot(self, checked: Checked) -> str:
        """The namespace of another robot of the graph a command is sent to by its names ("":
        this gateway's own robot)."""
        name = checked.command.name if checked.command else None
        return robot_under(name, self.latch_key, self.catalog)

    def _lease_refusal(self, checked: Checked) -> str | None:
        """Why another operator's control of the robot the command is sent to refuses it."""
        lease = self.lease
        if self.lease_of is not None and (other := self._other_robot(checked)):
            with self._leases_lock:
                if other not in self._leases:
                    self._leases[other] = self.lease_of(other)
                lease = self._leases[other]
        return lease.refusal(checked) if lease is not None else None

    def _adopt_speed_limits(self, checked: Checked, result: Execution) -> None:
        """A `param set` of the robot's own speed limit that went through becomes safety's
        clamp too (the robot's limit is the one it enforces; safety must not allow more)."""
        cmd = checked.command
        if result.error or cmd.key != ("param", "set"):
            return
        if cmd.args["param"] == "max_linear_speed":
            self.safety.max_linear = checked.message["value"]
        elif cmd.args["param"] == "max_angular_speed":
            self.safety.max_angular = checked.message["value"]
