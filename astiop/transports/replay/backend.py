"""A recorded session played back as a robot: the same state, events and map, read-only.

The playback clock runs on the recording's log time: `speed` recorded seconds per second, paused
at the end. Every command and teleop is refused ("replay is read-only"); nothing is sent.
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from typing import Any

from astiop.recording.reader import Recording, RobotView
from astiop.ros2.catalog import Catalog, astibot_catalog
from astiop.ros2.validation import Checked
from astiop.transports.base import BackendError, RobotTransport
from astiop.transports.inflight import InFlight
from astiop.transports.live_catalog import describe_graph, nothing_listed
from astiop.transports.state import (
    RobotEvent,
    RobotState,
    TopicStat,
    from_messages,
    grid_from_message,
)
from astiop.warehouse import default_map

READ_ONLY = "replay is read-only: nothing is sent to any robot"
SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)


class Playback:
    """Where the replay is: a cursor on the recording's clock, moving while playing."""

    def __init__(self, start_ns: int, end_ns: int, speed: float = 1.0, playing: bool = True):
        self.start_ns, self.end_ns = start_ns, end_ns
        self.speed = speed
        self.playing = playing
        self._cursor = start_ns
        self._anchor = time.monotonic()
        self._lock = threading.Lock()

    def now_ns(self) -> int:
        with self._lock:
            return self._advance()

    def _advance(self) -> int:
        if self.playing:
            now = time.monotonic()
            self._cursor += int((now - self._anchor) * self.speed * 1e9)
            self._anchor = now
            if self._cursor >= self.end_ns:
                self._cursor, self.playing = self.end_ns, False
        return self._cursor

    @property
    def position_s(self) -> float:
        return (self.now_ns() - self.start_ns) / 1e9

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / 1e9

    def toggle(self) -> bool:
        with self._lock:
            self._advance()
            if not self.playing and self._cursor >= self.end_ns:
                self._cursor = self.start_ns  # play again from the start
            self.playing = not self.playing
            self._anchor = time.monotonic()
            return self.playing

    def step(self, seconds: float) -> None:
        """Move the cursor and pause there."""
        with self._lock:
            self._advance()
            self.playing = False
            self._cursor = min(max(self._cursor + int(seconds * 1e9), self.start_ns), self.end_ns)

    def seek(self, position_s: float) -> None:
        with self._lock:
            self._advance()
            self._cursor = min(self.start_ns + round(position_s * 1e9), self.end_ns)
            self._anchor = time.monotonic()

    def faster(self, up: bool) -> float:
        with self._lock:
            self._advance()
            i = min(range(len(SPEEDS)), key=lambda k: abs(SPEEDS[k] - self.speed))
            self.speed = SPEEDS[min(max(i + (1 if up else -1), 0), len(SPEEDS) - 1)]
            return self.speed


def recorded_catalog(recording: Recording) -> Catalog:
    """The robot as it was recorded: another make's topics and roles (a TurtleBot3's pose from
    /amcl_pose and /tf) read off the recording's channels; the ASTIbot's own catalog for one of
    its sessions (its services and parameters listed as they were)."""
    lists = nothing_listed()
    lists["topic"] = sorted(
        (name, ch.type)
        for name, ch in recording.channels.items()
        if ch.type and ch.schema_encoding == "ros2msg" and not name.startswith("/astiop/")
    )
    types = {t for _, t in lists["topic"]}
    if not lists["topic"] or "astiop_msgs/msg/RobotStatus" in types:
        return astibot_catalog()
    lists["node"] = [("/recorded", "")]  # a recording keeps no node names: not the ASTIbot's
    return describe_graph(lists)


class ReplayBackend(RobotTransport):
    name = "replay"
    runs_commands = drives = False
    read_only = READ_ONLY

    def __init__(
        self,
        recording: Recording,
        *,
        store=None,
        speed: float = 1.0,
        paused=False,
        playback: Playback | None = None,
    ):
        self.recording = recording
        self.label = f"replay of {recording.path.name}"
        self.store = store  # a throwaway store: the recorded turns appear in it as they happen
        self.catalog: Catalog = recorded_catalog(recording)
        self.inflight = InFlight()  # stays empty: a replay never actuates
        # a fleet's robots share one clock: the first one's, which starts it
        self._own_clock = playback is None
        self.playback = playback or Playback(
            recording.start_ns, recording.end_ns, speed, not paused
        )
        self._turns = recording.channels.get("/astiop/interactions")
        self._turns_shown = 0
        self._map_index = -1  # which recorded /map message self._map was decoded from
        self._map = None
        self._events: list[RobotEvent] = []
        if recording.cut:
            cut = (
                f"the recording was cut off at {recording.duration_s:.1f} s: replaying up to there"
            )
            self._events.append(RobotEvent(1, recording.start_ns / 1e9, "replay", "warning", cut))
        ch = recording.channels.get("/astiop/events")
        logged = [(t_ns, ch.message(i)) for i, t_ns in enumerate(ch.times)] if ch else []
        for t_ns, ev in logged:
            self._events.append(
                RobotEvent(
                    len(self._events) + 1,
                    t_ns / 1e9,
                    str(ev.get("kind", "")),
                    str(ev.get("severity", "info")),
                    str(ev.get("message", "")),
                )
            )
        self._mission_events(recording)

    def _mission_events(self, recording: Recording) -> None:
        """The recorded missions' progress (start, each step's end, end) among the events, in
        the order it happened."""
        ch = recording.channels.get("/astiop/mission")
        logged = [(t_ns, ch.message(i)) for i, t_ns in enumerate(ch.times)] if ch else []
        for t_ns, rec in logged:
            bad = rec.get("status") not in (None, "succeeded", "skipped", "replaced")
            seq = len(self._events) + 1
            text = str(rec.get("text", ""))
            self._events.append(
                RobotEvent(seq, t_ns / 1e9, "mission", "warning" if bad else "info", text)
            )
        self._events.sort(key=lambda ev: ev.t)
        self._events = [replace(ev, seq=n) for n, ev in enumerate(self._events, 1)]

    # -- lifecycle, e-stop: there is no robot to stop ---------------------------------------
    def start(self) -> None:
        if self._own_clock:
            self.playback.seek(0.0)  # the clock starts when the console does, not at loading

    def close(self) -> None:
        pass

    @property
    def e_stopped(self) -> bool:
        status = self.recording.latest(["/robot_status"], self.playback.now_ns())
        return bool(status.get("/robot_status", {}).get("e_stopped", False))

    def estop(self) -> list[str]:
        return []  # nothing moves; the latch is kept in the replay's own store

    def release_estop(self, *, robot: bool = True) -> list[str]:
        return []

    def execute(self, checked: Checked, timeout: float) -> tuple[str, object]:
        raise BackendError(READ_ONLY)

    def drive(self, twist: dict) -> None:
        raise BackendError(READ_ONLY)

    def wait_until_idle(self, timeout_s: float) -> str | None:
        return None  # no goal is ever started here

    # -- the recorded state -------------------------------------------------------------------
    def state(self) -> RobotState:
        t_ns = self.playback.now_ns()
        self._show_turns(t_ns)
        messages = self.recording.latest(self.catalog.recorded_topics(), t_ns)
        seq = sum(1 for ev in self._events if ev.t * 1e9 <= t_ns)
        profile = self.catalog.profile  # None: the ASTIbot's names
        return from_messages(t_ns / 1e9, messages, event_seq=seq, profile=profile)

    def messages(self, names) -> dict[str, dict[str, Any]]:
        return self.recording.latest(names, self.playback.now_ns())

    def image(self, name: str):
        """A recording keeps a camera's compressed frames where the robot sent them
        (recording/writer.py `camera_topic`): read in place of the camera's own topic."""
        if name not in self.recording.channels and name + "/compressed" in self.recording.channels:
            name += "/compressed"
        return super().image(name)

    def message_times(self, names) -> dict[str, float]:
        t_ns = self.playback.now_ns()
        times = {}
        for name in names:
            ch = self.recording.channels.get(name)
            if ch is not None and (i := ch.index_at(t_ns)) >= 0:
                times[name] = ch.times[i] / 1e9
        return times

    def events_since(self, seq: int) -> list[RobotEvent]:
        t_ns = self.playback.now_ns()
        return [ev for ev in self._events if ev.seq > seq and ev.t * 1e9 <= t_ns]

    def topic_stats(self) -> list[TopicStat]:
        """Rates over the 2 recorded seconds before the cursor; age since the last message."""
        t_ns = self.playback.now_ns()
        stats = []
        for name, spec in self.catalog.topics.items():
            ch = self.recording.channels.get(name)
            i = ch.index_at(t_ns) if ch else -1
            if ch is None:
                stats.append(TopicStat(name, spec.type, spec.rate_hz, 0.0, float("inf"), 0))
                continue
            window = self.recording.count_between(name, t_ns - 2_000_000_000, t_ns)
            age = (t_ns - ch.times[i]) / 1e9 if i >= 0 else float("inf")
            stats.append(TopicStat(name, spec.type, spec.rate_hz, window / 2.0, age, i + 1))
        return stats

    def map_geometry(self):
        ch = self.recording.channels.get("/map")  # e.g. a bag recorded with ros2 bag
        if ch is None or not ch.times:
            return default_map() if self.recording.backend == "sim" else None
        # the /map at the cursor (the first one before it comes), decoded once per message: the
        # map view redraws from scratch whenever it is handed a different object
        index = max(ch.index_at(self.playback.now_ns()), 0)
        if index != self._map_index:
            try:
                grid = grid_from_message(ch.message(index))
            except (KeyError, TypeError, ValueError):
                grid = None
            self._map_index, self._map = index, grid
        return self._map

    # -- the recorded turns into the replay's store ----------------------------------------------
    def _show_turns(self, t_ns: int) -> None:
        if self.store is None or self._turns is None:
            return
        reached = self._turns.index_at(t_ns) + 1
        while self._turns_shown < reached:
            turn = self._turns.message(self._turns_shown)
            self.store.add_recorded_interaction(turn, self._turns.times[self._turns_shown] / 1e9)
            self._turns_shown += 1


def open_replay(path, *, store=None, speed: float = 1.0, paused: bool = False) -> ReplayBackend:
    return ReplayBackend(Recording(path), store=store, speed=speed, paused=paused)


def open_fleet_replay(
    recording: Recording, robots: list[tuple[str, str]], *, store=None, speed=1.0, paused=False
) -> list[ReplayBackend]:
    """A fleet session's robots, in `robots`' order, each seen inside its namespace, on one
    clock (the first robot's) and with the session's turns and missions once (the first's)."""
    first = ReplayBackend(
        RobotView(recording, robots[0][1], shared=True), store=store, speed=speed, paused=paused
    )
    others = [
        ReplayBackend(RobotView(recording, ns, shared=False), playback=first.playback)
        for _, ns in robots[1:]
    ]
    for backend, (name, _) in zip([first, *others], robots, strict=True):
        backend.label = f"replay of {recording.path.name}, {name}"
    return [first, *others]
