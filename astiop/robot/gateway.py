"""The one door to the robot: validate, review for safety, confirm, execute; and its live state.

The E-STOP is latched in the store, so every astiop process on that database refuses actuation
while it holds, and a restart keeps it. It is checked before the confirmation and again right
before anything is sent.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterable

from astiop.robot.camera import CameraReading, read_camera
from astiop.robot.command_journal import CommandJournal
from astiop.robot.estop_latch import ESTOP_REASON, EstopLatch
from astiop.robot.graph_reading import GraphReading
from astiop.robot.lease import Lease
from astiop.robot.provenance import date_reading, name_role, provenance
from astiop.robot.safety import Review, SafetyPolicy
from astiop.robot.station_latch import Act, StationLatch
from astiop.ros2.catalog import Catalog
from astiop.ros2.fleet_names import robot_under
from astiop.ros2.profile_types import Profile
from astiop.ros2.render import STAMPED
from astiop.ros2.validation import Checked, validate
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import TAKE
from astiop.store import Store
from astiop.transports.base import BackendError, Execution, MapGeometry, RobotTransport
from astiop.transports.playback import Playback, PlaysBack
from astiop.transports.state import RobotEvent, RobotState, TopicStat

Confirm = Callable[[Checked], bool]
log = logging.getLogger("astiop.robot")


class RobotGateway:
    def __init__(
        self,
        backend: RobotTransport,
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
        self.latch_key = latch_key  # a namespaced robot latches its own E-STOP (a fleet's)
        self.estop_latch = EstopLatch(
            backend, store, who=who, latch_key=latch_key, say_store_error=self._say_store_error
        )
        self.graph_reading = GraphReading(backend, self.safety, store, timeout_s)
        self.lease: Lease | None = None  # set where the robot is shared (ROS 2)
        # a fleet's robot reached through a whole-domain gateway by its names: its lease, made
        # by this (robot/factory.py) the first time a motion is sent to it
        self.lease_of: Callable[[str], Lease] | None = None
        self._leases: dict[str, Lease] = {}
        self._leases_lock = threading.Lock()
        self.use_map()
        if restore_latch:
            self.estop_latch.restore()
        self.estop_latch.watch_store()

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
        self.estop_latch.follow_stations(namespace)

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
        self.estop_latch.close()
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

    def messages(self, names: Iterable[str]) -> dict[str, dict]:
        """The latest message per topic, as the robot sent it (for recording)."""
        return self.backend.messages(names)

    def message_times(self, names: Iterable[str]) -> dict[str, float]:
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
            # it may have appeared since
            checked = self.graph_reading.checked_once_heard(text, checked)
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
        journal = CommandJournal(self.store, self._say_store_error, source) if source else None
        result = self._run(text, confirm, timeout, review, journal)
        if journal is not None and result.valid:
            journal.finish(result)
        return result

    def record(self, ex: Execution, source: str) -> None:
        CommandJournal(self.store, self._say_store_error, source).finish(ex)

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
        cmd = checked.command
        assert cmd is not None  # allowed: valid, so parsed
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
        if checked.kind == "actuate" and self.estop_latch.held_by_estop(checked):
            result.reason = ESTOP_REASON  # pressed while the operator was deciding
            return result
        if journal is not None:
            journal.sent(result)  # before the robot is told: a crash meanwhile leaves its record
        try:
            result.output, result.values = self.backend.execute(checked, timeout or self.timeout_s)
            result.executed = True
            result.provenance = provenance(cmd, checked.kind, self.catalog)
            name_role(cmd.name, result, self.profile)
            if VERBS[cmd.key].runs_as == TAKE:  # one message: its age is known
                date_reading(cmd.name, result, self.catalog, self.backend.robot_time())
        except BackendError as exc:
            result.executed = True
            result.error = str(exc)
            result.output = f"error: {exc}\n"
        if not result.error:
            self.safety.adopt_robot_limit(cmd, checked.message)
        result.duration_s = time.perf_counter() - t0
        return result

    def cancel_goals(self) -> None:
        """Cancel the goals this process sent and that run (a mission's cancel on a Nav2 robot,
        whose navigation drives on through a zero velocity), journaled as the operator's: a
        goal cancelled here is no one else's (the built-in alerts read the journal)."""
        self.backend.cancel_goals()
        if self.store is not None:
            try:
                self.store.add_command(
                    None, command="cancel the goals this station sent", valid=1, executed=1,
                    kind="actuate",
                )  # fmt: skip
            except Exception as exc:  # noqa: BLE001 - said; the cancel itself went out
                self._say_store_error(f"the cancel was not journaled: {exc}")

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
        if self.estop_latch.held_by_estop(review.checked):
            result.reason = ESTOP_REASON
            return result
        result.notes = list(review.checked.notes)
        message = review.checked.message
        assert message is not None  # allowed: its values were checked
        try:
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

    # -- the E-STOP (robot/estop_latch.py) ---------------------------------------------------
    @property
    def station_latch(self) -> StationLatch | None:
        return self.estop_latch.station_latch

    @property
    def latched(self) -> bool:
        return self.estop_latch.latched

    @property
    def e_stopped(self) -> bool:
        return self.estop_latch.e_stopped

    def estop(self, at: float | None = None, who: str | None = None) -> list[str]:
        return self.estop_latch.estop(at, who)

    def release_estop(self, pressed: Act | None = None) -> list[str]:
        return self.estop_latch.release_estop(pressed)

    def pressed_by(self) -> Act | None:
        return self.estop_latch.pressed_by()

    def follow_latch(self) -> bool:
        return self.estop_latch.follow_latch()

    def warm_estop(self) -> None:
        self.estop_latch.warm_estop()

    def zero_now(self) -> None:
        self.estop_latch.zero_now()

    def settle_estop(self, timeout_s: float) -> list[str]:
        return self.estop_latch.settle_estop(timeout_s)

    # -- the robot's graph (robot/graph_reading.py) ------------------------------------------
    @property
    def catalog(self) -> Catalog:
        return self.graph_reading.catalog

    @property
    def profile(self) -> Profile:
        return self.graph_reading.profile

    def use_map(self) -> None:
        self.graph_reading.use_map()

    def settled_profile(self, timeout_s: float) -> Profile:
        return self.graph_reading.settled_profile(timeout_s)

    def confirm_missing(self) -> Profile:
        return self.graph_reading.confirm_missing()

    def serves(self, name: str, timeout_s: float) -> bool:
        return self.graph_reading.serves(name, timeout_s)
