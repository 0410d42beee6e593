"""The gateway's E-STOP, latched in the store: every astiop process on that database refuses
actuation while it holds, and a restart keeps it."""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from astiop.robot.latch_watch import LatchWatcher
from astiop.robot.safety import always_allowed
from astiop.robot.station_latch import Act, StationLatch
from astiop.ros2.validation import Checked
from astiop.store import Store
from astiop.transports.base import RobotTransport

log = logging.getLogger("astiop.robot")
HELD_FOR_ALL = (
    "the E-STOP of every robot on this database still holds it: astiop estop --release --all"
)
ESTOP_REASON = "the E-STOP is engaged: no motion command runs until the operator releases it"


class EstopLatch:
    """One robot's E-STOP for the gateway that holds it: the robot told first, then the robot's
    graph (every station), then the store (every process on this database). It is handed the
    robot's backend, the store (None: the graph's word and this process's memory alone), who
    presses, the latch's key (a fleet's robot: its namespace) and where a store error is said."""

    def __init__(
        self,
        backend: RobotTransport,
        store: Store | None,
        *,
        who: str,
        latch_key: str = "",
        say_store_error: Callable[[str], None],
    ):
        self.backend = backend
        self.store = store
        self.who = who
        self.latch_key = latch_key  # a namespaced robot latches its own E-STOP (a fleet's)
        self._say_store_error = say_store_error
        self.station_latch: StationLatch | None = None  # the latch on the robot's graph
        self._lock = threading.Lock()
        self._seen = False
        self._seen = self.latched
        self._watcher: LatchWatcher | None = None

    def restore(self) -> None:
        """A restart keeps the E-STOP until it is released: the robot is stopped again."""
        if self._seen and not self.backend.e_stopped:
            self.backend.estop()

    def watch_store(self) -> None:
        """Another process's E-STOP ends what this one has in flight, with no one asking."""
        if self.store is not None:
            self._watcher = LatchWatcher(
                self.store, self.backend.inflight, self.follow_latch
            ).start()

    def follow_stations(self, namespace: str) -> None:
        """Follow the E-STOP that every station says on the robot's graph, and say this one's
        (robot/station_latch.py), where the transport can reach the graph."""
        backend = self.backend
        self.station_latch = StationLatch(
            lambda heard: backend.estop_channel(namespace, heard), self.follow_latch
        ).start()

    def close(self) -> None:
        if self._watcher is not None:
            self._watcher.close()
        if self.station_latch is not None:
            self.station_latch.close()

    @property
    def latched(self) -> bool:
        """The latch: the robot's graph's (every station's), the store's (every robot's, or this
        robot's own); a store that cannot be read counts as latched while this process holds."""
        graph = self.station_latch
        if graph is not None and graph.engaged:
            return True
        if graph is None and self.store is None:
            return self._seen  # this process alone: its own press holds until it releases it
        try:
            return self._store_latch() is not None
        except Exception as exc:  # noqa: BLE001 - a damaged or vanished file: memory decides
            self._say_store_error(f"the E-STOP latch could not be read: {exc}")
            return self._seen

    def _store_latch(self) -> dict[str, Any] | None:
        store = self.store
        if store is None:
            return None
        own = store.robot_latch(self.latch_key) if self.latch_key else None
        return own or store.estop_latch()

    @property
    def e_stopped(self) -> bool:
        return self.backend.e_stopped or self.latched

    def estop(self, at: float | None = None, who: str | None = None) -> list[str]:
        """Stop the robot, then say it on its graph, then latch it for every process on this
        database; the steps that failed. `at`: when it was pressed (a press's later steps name
        the same press, and never undo a release made after it)."""
        act = Act.here(who or self.who, at)
        failures = self.backend.estop()  # the robot first: nothing may delay it
        with self._lock:  # the sampler's follow_latch must not undo it
            self._seen = True
            if self.station_latch is not None:
                self.station_latch.pressed(act)
            if self.store is not None:
                try:
                    self._latch_store(act)
                except Exception as exc:  # noqa: BLE001 - said; the stop itself went out
                    failures.append(f"the E-STOP is not latched in the database: {exc}")
        return failures

    def _latch_store(self, act: Act) -> bool:
        store, who = self.store, act.who
        assert store is not None
        if self.latch_key:
            return store.latch_robot(self.latch_key, who, act.at)
        return store.latch_estop(who, act.at)

    def _release_store(self, act: Act) -> None:
        store = self.store
        assert store is not None
        if self.latch_key:
            store.release_robot(self.latch_key, act.who, act.at)
        else:
            store.release_estop(act.who, act.at)

    def release_estop(self, pressed: Act | None = None) -> list[str]:
        """Release the latch for every station and every process on this database, then this
        process's robot; the failures. `pressed`: the press the person was shown (a press made
        since is not released). A fleet's robot releases its own latch; one on every robot
        still holds it."""
        graph = self.station_latch
        newer = graph.press if graph is not None else None
        if pressed is not None and newer is not None and newer.at > pressed.at:
            return [f"pressed again since, by {newer.words}: not released"]
        act = Act.here(self.who)
        with self._lock:
            if self.store is not None:
                self._release_store(act)
                if self.latch_key and self.store.estop_latch() is not None:
                    return [HELD_FOR_ALL]
            if graph is not None:
                graph.released(act)
            self._seen = False
        return self.backend.release_estop()

    def pressed_by(self) -> Act | None:
        """The newest press the robot's graph knows of (None: not said on it)."""
        graph = self.station_latch
        if graph is not None:
            graph.wait_ready()
            return graph.press if graph.engaged else None
        return None

    def follow_latch(self) -> bool:
        """Whether the E-STOP is latched; when another process (a second console, `astiop
        estop`, another station on the robot's graph) latched or released it since the last
        look, this process's robot follows, and so does this database."""
        with self._lock:  # read and acted on together: an estop() meanwhile waits
            self._adopt_graph()
            latched = self.latched
            if latched != self._seen:
                self._seen = latched
                if latched and not self.backend.e_stopped:
                    self.backend.estop()
                elif not latched and self.backend.e_stopped:
                    self.backend.release_estop(robot=False)  # the releaser told the robot
            if not latched and self.store is not None:
                self._end_what_moves_latched_robots()
        return latched

    def _adopt_graph(self) -> None:
        """This database and the robot's graph agree: a release said on the graph after this
        database's press releases it, and this database's own press or release (made by a
        process that does not hear the graph) is said there. A press heard on the graph holds
        this process while it is said, and is not written here: a station that was not running
        when it was released would raise it again."""
        graph, store = self.station_latch, self.store
        if graph is None or store is None or not graph.on_graph:
            return
        try:
            mine = self._store_latch()
            if mine is not None and not graph.engaged:
                release = graph.release
                if release is not None and release.at > float(mine["at"] or 0):
                    self._release_store(Act(release.at, f"{release.who} on {release.host}",
                                            release.host, release.pid))  # fmt: skip
                else:  # latched here (another process on this database): said on the graph
                    graph.pressed(Act(float(mine["at"] or time.time()), str(mine["by"]),
                                      *_here()))  # fmt: skip
            elif mine is None and graph.engaged and graph.press is not None:
                released = self._store_release()
                if released is not None and released.at > graph.press.at:
                    graph.released(released)  # released here, after that press
        except Exception as exc:  # noqa: BLE001 - the graph's word still holds this process
            self._say_store_error(f"the E-STOP on the robot's graph is not in the database: {exc}")

    def _store_release(self) -> Act | None:
        store = self.store
        assert store is not None
        if self.latch_key:
            row = store.robot_release(self.latch_key)
            by, at = (row["by"], row["at"]) if row else (None, None)
        else:
            record = store.estop_record()
            by, at = record.get("released_by"), record.get("released_at")
        return Act(float(at), str(by), *_here()) if at is not None else None

    def warm_estop(self) -> None:
        """Make ready what the E-STOP sends, so a press later goes out at once (a server's
        button: its publisher matched with the robot's base before anyone presses)."""
        self.backend.warm_estop()

    def zero_now(self) -> None:
        """A zero velocity sent at once, nothing else (a fleet's E-STOP sends every robot's
        before the rest of each one's stop); never raises: the E-STOP that follows says why."""
        with contextlib.suppress(Exception):
            self.backend.zero_now()

    def settle_estop(self, timeout_s: float) -> list[str]:
        """Wait for what the E-STOP started in the background to go out (a process about to
        exit); the failures that came meanwhile."""
        return self.backend.settle_estop(timeout_s)

    def _end_what_moves_latched_robots(self) -> None:
        """What this process has in flight on another robot of the fleet, reached by its names,
        ends when that robot's own E-STOP latches (in any process)."""
        inflight = self.backend.inflight
        if not inflight.busy:
            return
        latched = self._latched_robots()
        if latched:
            ended = inflight.end_where(lambda name: any(_under(name, ns) for ns in latched))
            for failure in ended:
                log.error(failure)

    def held_by_estop(self, checked: Checked) -> bool:
        """Latched (this robot, or the fleet's robot the command is sent to), and not a command
        the E-STOP always lets through (/stop)."""
        if always_allowed(checked):
            return False
        if self.station_latch is not None:  # a new station hears the others first
            self.station_latch.wait_ready()
        if self.e_stopped:
            return True
        name = checked.command.name if checked.command else None
        if not name:
            return False
        return any(_under(name, ns) for ns in self._latched_robots())

    def _latched_robots(self) -> list[str]:
        """The namespaces of every robot whose own E-STOP is latched (none without a store)."""
        return self.store.latched_robots() if self.store is not None else []


def _here() -> tuple[str, int]:
    act = Act.here("")
    return act.host, act.pid


def _under(name: str, namespace: str) -> bool:
    """Whether `name` is inside `namespace` ("/tb3_1/cmd_vel" is inside "/tb3_1")."""
    return name.startswith(namespace.rstrip("/") + "/")
