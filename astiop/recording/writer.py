"""Sessions recorded as MCAP, readable by Foxglove and `ros2 bag`.

The robot's state topics are written as ROS 2 messages: `ros2msg` schemas built from astiop's
interface definitions (the distro's), CDR-encoded by `mcap-ros2-support`. The agent's turns and
the robot's events go on JSON channels with a JSON schema, and so do the missions (their start,
each step's end, their end: /astiop/mission) and the alerts (/astiop/alerts). Log time is the
robot's clock: when the message was published (sim time on the simulator) or received (on the
robot).

A chunk is closed and flushed at least every FLUSH_S, so a recording killed at any moment keeps
everything up to its last chunk; `repair` (files.py) rewrites what such a file still holds.
"""

from __future__ import annotations

import contextlib
import json
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mcap.writer import Writer

from astiop.bounded import one_line
from astiop.recording import alerts, missions
from astiop.recording.schemas import JSON_SCHEMAS, ros2msg

FLUSH_S = 2.0
CAMERA_PERIOD_S = 1.0  # a camera's frames kept at most once a second: what a session file bears
POLL_HZ = 20.0
STOP_WAIT_S = 5.0  # for the thread's last poll; the file is finished either way
MAX_NOTICES = 5  # different failures said per recording; the same one is said once


class RecordingError(Exception):
    """The recording could not be written or read; one line says why."""


def session_metadata(gateway, fleet: list[tuple[str, str]] | None = None) -> dict[str, str]:
    """Which robot, and the two clocks at the start: the robot's and the wall's, so a sim-time
    recording can be placed in wall time (export); a fleet's robots, [[name, namespace], …]."""
    from astiop.ros2.grammar import current_distro

    meta = {
        "backend": gateway.kind,
        "distro": current_distro(),
        "robot_t0": repr(gateway.state().t),
        "wall_t0": repr(time.time()),
    }
    if fleet:
        meta["fleet"] = json.dumps([list(robot) for robot in fleet])
    return meta


class SessionRecorder:
    """Polls the gateway (never the simulator) and the store while it runs, in its own thread.

    A fleet's session (`fleet()`: its robots now, (name, namespace), and `gateway_of(name)`,
    None for a robot not reached yet) records every robot: its topics by their full names, under
    its namespace, and its events on `<namespace>/astiop/events`. A robot found after the
    recording began is recorded from then, and the metadata's list of robots written again.

    A poll that fails is said once (`on_error`, called from the recording's thread, and a line
    on stderr) and the recording goes on; `stop()` finishes the file whatever the polls did."""

    def __init__(
        self,
        path: Path,
        gateway,
        store=None,
        *,
        scan_hz: float | None = None,
        flush_s: float = FLUSH_S,
        on_error: Callable[[str], None] | None = None,
        fleet: Callable[[], list[tuple[str, str]]] | None = None,
        gateway_of: Callable[[str], Any] | None = None,
    ):
        from mcap_ros2._dynamic import serialize_dynamic  # the encoder its Writer uses

        self.path = Path(path)
        self.gateway = gateway
        self.store = store
        self.scan_period = 1.0 / scan_hz if scan_hz else 0.0
        self.flush_s = flush_s
        self._serialize = serialize_dynamic
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = self.path.open("wb")
        except OSError as exc:
            raise RecordingError(f"cannot write {self.path}: {exc.strerror or exc}") from None
        self._writer = Writer(self._file)
        self._writer.start(profile="ros2", library="astiop")
        self._fleet = fleet
        self._listed = fleet() if fleet else []  # the robots the metadata lists
        self._meta = session_metadata(gateway, self._listed)
        self._writer.add_metadata("astiop", self._meta)
        self._gateway_of = gateway_of or (lambda _name: None)
        self._channels: dict[str, tuple[int, Any]] = {}  # topic -> (channel id, encoder)
        self._last: dict[str, int] = {}  # topic -> last stamp written (ns)
        self.counts: dict[str, int] = {}
        self.failures = 0  # polls (or messages) that could not be written
        self._on_error = on_error
        self._said: set[str] = set()
        self._event_seq: dict[str, int] = {}  # per robot (its namespace): the last event seen
        self._camera_at: dict[str, float] = {}  # per robot: when its camera was last read
        for ns, gw in self._robots() if gateway else ():
            self._event_seq[ns] = gw.state().event_seq
        # The agent's turns: those after _turns_after, and those seen running (a turn ends when
        # it ends, not in the order the turns started), so each is written once, when it ends.
        self._turns_after, self._turns_running = self._interaction_marks()
        self._missions = missions.MissionLog(store)
        self._alerts = alerts.AlertLog(store)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._flushed = time.monotonic()
        self._lock = threading.Lock()  # the writer: a poll's writes, and finishing the file
        self._finished = False

    # -- the loop -----------------------------------------------------------------------
    def start(self) -> SessionRecorder:
        self._thread = threading.Thread(target=self._loop, name="astiop-record", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> dict[str, int]:
        """A last poll, then the file finished (its summary written), even after failed polls
        or a thread stuck in a robot call; RecordingError only if the file cannot be written."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(STOP_WAIT_S)  # it polls once more on its way out
        else:
            self._poll_safely()
        with self._lock:
            if not self._finished:
                self._finished = True  # a poll still under way writes nothing more
                try:
                    try:
                        self._writer.finish()
                    finally:
                        self._file.close()
                except (OSError, ValueError) as exc:
                    raise RecordingError(f"cannot finish {self.path}: {one_line(exc)}") from None
        return dict(self.counts)

    def _loop(self) -> None:
        while not self._stop.wait(1.0 / POLL_HZ):
            self._poll_safely()
        self._poll_safely()

    def _poll_safely(self) -> None:
        try:
            self.poll()
        except Exception as exc:  # any layer's: the recording must outlive one bad poll
            self._failed("a poll", exc)

    def _failed(self, what: str, exc: Exception) -> None:
        """Counted always; said once per different reason, up to MAX_NOTICES."""
        self.failures += 1
        reason = one_line(exc, 200) or type(exc).__name__
        if reason in self._said or len(self._said) >= MAX_NOTICES:
            return
        self._said.add(reason)
        text = f"recording {self.path.name}: {what} failed ({reason}); the recording goes on"
        print(f"astiop: {text}", file=sys.stderr, flush=True)
        if self._on_error is not None:
            with contextlib.suppress(Exception):  # the notice's own path (an app closing)
                self._on_error(text)

    def poll(self) -> None:
        """Write what is new since the last poll; close a chunk every flush_s. The robot and the
        store are read before the writer is locked: a call that hangs never holds up stop(),
        and a call that fails leaves everything to the next poll."""
        robots = [self._read(ns, gw) for ns, gw in self._robots()]
        robot_now = robots[0][1]  # the clock the store's records are logged on
        turns = self._interactions()
        mission_records = self._missions.poll()
        alert_records = self._alerts.poll()
        with self._lock:
            if self._finished:
                return
            self._list_the_fleet()
            for gateway, now, messages, times, events, ns in robots:
                topics = gateway.catalog.topics
                for topic, message in messages.items():
                    kept = _under(ns, topic)
                    stamp = times.get(topic, now)
                    self._topic_message(gateway, topic, kept, topics[topic].type, message, stamp)
                for ev in events:
                    data = {"kind": ev.kind, "severity": ev.severity, "message": ev.message}
                    self._json(
                        _under(ns, "/astiop/events"),
                        data,
                        int((ev.t or now) * 1e9),
                        "/astiop/events",
                    )
                    self._event_seq[ns] = max(self._event_seq.get(ns, 0), ev.seq)
            for turn in turns:
                self._interaction(turn, int(robot_now * 1e9))
            for record in mission_records:
                self._json(missions.TOPIC, record, int(robot_now * 1e9))
            for record in alert_records:
                self._json(alerts.TOPIC, record, int(robot_now * 1e9))
            if time.monotonic() - self._flushed >= self.flush_s:
                self._writer.flush()  # closes the open chunk: a kill from here on loses nothing
                self._file.flush()
                self._flushed = time.monotonic()

    def _robots(self) -> list[tuple[str, Any]]:
        """(namespace, gateway) of every robot recorded: the gateway's alone, or the fleet's
        reached so far (the current robot's first: its clock logs the store's records)."""
        if self._fleet is None:
            return [("", self.gateway)]
        fleet = self._fleet()
        reached = [(ns, self._gateway_of(name)) for name, ns in fleet]
        current = [(ns, gw) for ns, gw in reached if gw is self.gateway] or [("", self.gateway)]
        others = [(ns, gw) for ns, gw in reached if gw is not None and gw is not self.gateway]
        return current + others

    def _list_the_fleet(self) -> None:
        """The metadata written again when robots joined (a reader keeps the last)."""
        fleet = self._fleet() if self._fleet is not None else []
        if fleet and fleet != self._listed:
            self._listed = fleet
            self._meta["fleet"] = json.dumps([list(robot) for robot in fleet])
            self._writer.add_metadata("astiop", dict(self._meta))

    def _read(self, ns: str, gateway) -> tuple:
        """One robot's new messages and events, read before the writer is locked."""
        if ns not in self._event_seq:  # a robot reached after the recording began: from now
            self._event_seq[ns] = gateway.state().event_seq
        now = gateway.state().t
        names = gateway.catalog.recorded_topics()
        camera = camera_topic(gateway.catalog)
        if camera and now - self._camera_at.get(ns, -CAMERA_PERIOD_S) >= CAMERA_PERIOD_S:
            self._camera_at[ns] = now  # its frame read and kept once a period, not each poll
            names = [*names, camera]
        times = gateway.message_times(names)  # published, or received on a robot
        messages = gateway.messages(names)
        return gateway, now, messages, times, gateway.events_since(self._event_seq[ns]), ns

    def _topic_message(self, gateway, topic, kept, type_name, message, t) -> None:
        """`topic` as the gateway names it, `kept` as it is recorded (under its namespace)."""
        stamp = int(t * 1e9)
        last = self._last.get(kept)
        if last is not None and stamp <= last:
            return  # nothing new on this topic
        scan = gateway.catalog.profile.name("scan") if gateway.catalog.profile else None
        if (
            topic == (scan or "/scan")
            and last is not None
            and stamp - last < self.scan_period * 1e9
        ):
            return
        self._last[kept] = stamp  # a message that cannot be encoded is passed over, once
        try:
            self._ros2(kept, type_name, message, stamp)
        except Exception as exc:  # the encoder's: a message that does not fit its type
            self._failed(f"writing {kept}", exc)

    # -- writing ------------------------------------------------------------------------
    def _channel(self, topic: str, type_name: str) -> tuple[int, Any]:
        if topic not in self._channels:
            text = ros2msg(type_name)
            schema_id = self._writer.register_schema(type_name, "ros2msg", text.encode())
            channel_id = self._writer.register_channel(topic, "cdr", schema_id)
            encoder = self._serialize(type_name, text)[type_name]
            self._channels[topic] = (channel_id, encoder)
        return self._channels[topic]

    def _ros2(self, topic: str, type_name: str, message: dict, stamp: int) -> None:
        channel_id, encode = self._channel(topic, type_name)
        data = encode(_finite_floats(message))
        self._writer.add_message(channel_id, stamp, data, stamp)
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def _json(self, topic: str, data: dict, t_ns: int, kind: str = "") -> None:
        if topic not in self._channels:
            schema = json.dumps(JSON_SCHEMAS[kind or topic]).encode()
            schema_id = self._writer.register_schema(topic.split("/")[-1], "jsonschema", schema)
            self._channels[topic] = (self._writer.register_channel(topic, "json", schema_id), None)
        channel_id = self._channels[topic][0]
        payload = json.dumps(data, default=str).encode()
        self._writer.add_message(channel_id, t_ns, payload, t_ns)
        self.counts[topic] = self.counts.get(topic, 0) + 1

    # -- the agent's turns ----------------------------------------------------------------
    def _interaction_marks(self) -> tuple[int, set[int]]:
        """Turns that ended before the recording are not in it; those running are, later."""
        if self.store is None:
            return 0, set()
        newest, running = self.store.interaction_marks()
        return newest, set(running)

    def _interactions(self) -> list[dict]:
        if self.store is None:
            return []
        return self.store.interactions_to_record(self._turns_after, self._turns_running)

    def _interaction(self, turn: dict, t_ns: int) -> None:
        if turn["status"] == "running":
            self._turns_running.add(turn["id"])
        else:
            self._json("/astiop/interactions", turn, t_ns)
            self._turns_running.discard(turn["id"])
        self._turns_after = max(self._turns_after, turn["id"])


def _under(namespace: str, topic: str) -> str:
    """A fleet robot's topic under its namespace (a robot of this process names it without)."""
    if not namespace or topic.startswith(namespace + "/"):
        return topic
    return namespace + topic


def _finite_floats(value: Any) -> Any:
    """CDR carries inf and nan; YAML-read messages may hold them as strings ('.inf')."""
    if isinstance(value, dict):
        return {k: _finite_floats(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite_floats(v) for v in value]
    if isinstance(value, str) and value in (".inf", "-.inf", ".nan", "inf", "-inf", "nan"):
        return float(value.replace(".", ""))
    return value


def default_path(data_dir: Path) -> Path:
    return data_dir / "sessions" / (time.strftime("%Y%m%d-%H%M%S") + ".mcap")


def camera_topic(catalog) -> str | None:
    """The topic a recording keeps of the robot's camera: its compressed frames where the robot
    publishes them (image_transport's `<camera>/compressed`), else the camera's own."""
    profile = catalog.profile
    name = profile.name("camera") if profile is not None else None
    if name is None or profile.kind("camera") != "topic":
        return None
    compressed = catalog.topics.get(name + "/compressed")
    if compressed is not None and compressed.type == "sensor_msgs/msg/CompressedImage":
        return compressed.name
    return name
