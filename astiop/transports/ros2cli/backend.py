"""The real robot: the same checked commands, run by the `ros2` executable (never a shell).

Live state comes from long-lived `ros2 topic echo` streams; long-running verbs run under
`Popen` and are stopped with SIGINT so the real client cancels what it started.
"""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Callable
from typing import Any

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import current_distro
from astiop.ros2.profile import ProfileSpec
from astiop.ros2.transforms import STALE_S, TransformTable
from astiop.ros2.validation import Checked
from astiop.transports import live_robot
from astiop.transports.base import BackendError, RobotTransport
from astiop.transports.event_log import Contact, EventLog
from astiop.transports.images import ImageMessage
from astiop.transports.inflight import InFlight, Job
from astiop.transports.live_catalog import LiveGraph, nothing_listed
from astiop.transports.live_robot import without_finished_plan
from astiop.transports.ros2cli import process as ros2_process
from astiop.transports.ros2cli.commands import CliCommands
from astiop.transports.ros2cli.estop import CliEstop
from astiop.transports.ros2cli.graph import GraphReader
from astiop.transports.ros2cli.motion import STDIN_DISTROS, TeleopPublisher
from astiop.transports.ros2cli.streams import TopicStream, parse_document
from astiop.transports.state import (
    GOAL_STATUS,
    OccupancyGrid,
    RobotEvent,
    RobotState,
    TopicStat,
    from_messages,
    goal_status_topic,
    grid_from_message,
    live_topic_stats,
)

ARRAYS = {"/scan", "/plan", "/obstacles"}  # echoed in full: ros2 truncates at 128 items
GRAPH_REFRESH_S = 30.0
DISCOVERY_YOUNG_S = 10.0  # a process this young may not have the whole robot in its lists
NO_GOAL_AFTER_S = 5.0  # a latched goal status echoed this long and none came: no goal yet


class Ros2Backend(RobotTransport):
    name = "ros2"

    def __init__(
        self,
        executable: str = "ros2",
        timeout_s: float = 10.0,
        *,
        stream: bool = True,
        discover: bool = True,
        fixed: ProfileSpec | None = None,
    ):
        """`discover=False` (an E-STOP from a new process): the graph is not read first (a
        `daemon start`, then up to three rounds of five list calls: 10-25 s with the real CLI)."""
        path = shutil.which(executable)
        if path is None:
            raise BackendError(
                f"'{executable}' was not found on PATH: source your ROS 2 setup "
                "(e.g. /opt/ros/jazzy/setup.bash) or use --robot sim"
            )
        self.executable = path
        self.timeout_s = timeout_s
        self.distro = current_distro()
        self.stream = stream
        self.inflight = InFlight()
        self._teleop_job: Job | None = None  # while teleop holds a velocity
        self._lock = threading.Lock()
        self._latest: dict[str, dict[str, Any]] = {}
        self._received: dict[str, float] = {}  # on the robot clock: s since t0
        self._streams: dict[str, TopicStream] = {}
        self._goal_stream_at: float | None = None  # when the goal status echo started
        self._transforms: dict[str, TransformTable] = {}  # /tf, /tf_static: fed by one stream each
        self._map: OccupancyGrid | None = None
        self._teleop: TeleopPublisher | None = None
        self.t0 = time.monotonic()
        self.events = EventLog(self.t0)
        self._closed = threading.Event()
        fixed = fixed or ProfileSpec()  # what the operator fixed: a file, a namespace
        self._graph = GraphReader(self._run, timeout_s, fixed)
        catalog = self._graph.read() if discover else self._graph.describe(nothing_listed())
        self._live = LiveGraph(catalog, fixed)
        self._live.discovered = discover
        self.refreshed_at = time.monotonic()
        self._commands = CliCommands(self._run, path, self.inflight, self.events)
        self._estop = CliEstop(self._run, self._live, self.inflight, self.events, timeout_s)
        # the robot back: the E-STOP's armed publisher may have ended with it
        self._contact = Contact(self.events, on_return=self._estop.rearm)

    # -- the live graph -----------------------------------------------------------------
    @property
    def catalog(self) -> Catalog:
        return self._live.catalog

    @catalog.setter
    def catalog(self, catalog: Catalog) -> None:
        self._live.catalog = catalog

    @property
    def discovered(self) -> bool:
        """Whether the robot's graph was read (an E-STOP from a new process does not wait)."""
        return self._live.discovered

    def _name(self, role: str, default: str = "") -> str:
        return self._live.name(role, default)

    def _run(
        self,
        argv: list[str],
        timeout: float,
        *,
        until: Callable[[str], bool] | None = None,
        cancel: threading.Event | None = None,
        cancellable: Callable[[str], bool] | None = None,
    ) -> ros2_process.Run:
        """`ros2 ARGV`; inside an actuating command's job, the E-STOP kills it."""
        job = self.inflight.current_job()
        return ros2_process.run(
            self.executable, argv, timeout,
            until=until, job=job, cancel=cancel, cancellable=cancellable,
        )  # fmt: skip

    def discovering(self) -> bool:
        # a new process's first lists (the daemon's, or a fresh discovery) may be partial
        return time.monotonic() - self.t0 < DISCOVERY_YOUNG_S

    def refresh(self, settle: bool = True) -> bool:
        """Read the graph again (a name was missing, or 30 s passed); False if it failed.
        Each read is a `ros2` process of its own, settled or not."""
        try:
            self.catalog = self._graph.describe(self._graph.lists())
        except BackendError:
            return False
        self.refreshed_at, self._live.discovered = time.monotonic(), True
        return True

    def _refresh_loop(self) -> None:
        while not self._closed.wait(GRAPH_REFRESH_S):
            self.refresh()

    # -- lifecycle ------------------------------------------------------------------------
    def start(self) -> None:
        cmd_vel = self.catalog.topics.get(self._name("velocity_command"))
        if cmd_vel is not None:
            self._teleop = TeleopPublisher(
                self.executable, cmd_vel.name, cmd_vel.type, on_lapse=self._teleop_lapsed
            )
            self._estop.teleop = self._teleop  # the E-STOP halts it
            if self.distro in STDIN_DISTROS:
                self._estop.arm(self.executable, cmd_vel.name, cmd_vel.type)
        if not self.stream:
            return
        # odometry only when it is the pose (50 Hz of YAML costs more than it tells)
        names = self.catalog.state_topics()
        odom = self._name("odometry")
        if odom in names and self._name("pose") != odom and self._name("status"):
            names.remove(odom)
        for name in names:
            extra = ("--full-length",) if name in ARRAYS else ()
            spec = self.catalog.topics[name]
            self._streams[name] = TopicStream(
                self.executable, name, spec.type, self._on_message, self.events.add, extra
            ).start()
        goals = goal_status_topic(self.catalog.profile)
        if goals:  # a Nav2 robot's state word: does its action run a goal (a hidden topic)
            self._streams[goals] = TopicStream(
                self.executable, goals, GOAL_STATUS, self._on_message, self.events.add
            ).start()
            self._goal_stream_at = time.monotonic()
        if self._name("map"):
            threading.Thread(target=self._read_map, name="ros2-map", daemon=True).start()
        threading.Thread(target=self._refresh_loop, name="ros2-graph", daemon=True).start()

    def close(self) -> None:
        self._closed.set()
        for s in self._streams.values():
            s.stop()
        self._streams.clear()
        if self._teleop is not None:
            self._teleop.close()
        self._estop.close()
        self._commands.close()

    # -- live state -----------------------------------------------------------------------
    def _on_message(self, name: str, msg: dict[str, Any], received: float) -> None:
        if name == self._name("status"):
            self.events.status(str(msg.get("state")), str(msg.get("fault") or ""))
        if name in (self._name("transforms"), self._name("static_transforms")):
            static = name == self._name("static_transforms")
            table = self._transforms.setdefault(name, TransformTable(None if static else STALE_S))
            table.fold(msg, received)  # the tree so far, not this message's few transforms
            msg = table.message(received) or msg
        with self._lock:
            self._latest[name] = msg
            self._received[name] = received - self.t0

    def robot_time(self) -> float:
        return time.time()  # ros2 runs on this machine's clock, as the robot's drivers do

    def state(self) -> RobotState:
        with self._lock:
            messages = dict(self._latest)
        seq = self.events.seq
        profile = self.catalog.profile
        goals = goal_status_topic(profile)
        # the status is latched (rcl_action): an echo running this long without one means its
        # server has had no goal; before that (a `ros2` starting up) the state is not known
        since = self._goal_stream_at
        waited = since is not None and time.monotonic() - since > NO_GOAL_AFTER_S
        if goals in self._streams and goals not in messages and waited:
            messages[goals] = {"status_list": []}
        messages = without_finished_plan(messages, profile)
        now = time.monotonic()
        state = from_messages(
            now - self.t0, messages, e_stopped=self.inflight.held, event_seq=seq, profile=profile
        )
        return state.with_lost(self._lost_for(now))

    def _lost_for(self, now: float) -> float | None:
        """Seconds since the robot was last heard, when it is lost (said once, as is its
        return)."""
        return self._contact.check([s.age(now) for s in self._streams.values()])

    def messages(self, names) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {n: self._latest[n] for n in names if n in self._latest}

    def message_times(self, names) -> dict[str, float]:
        with self._lock:
            return {name: self._received[name] for name in names if name in self._received}

    def image(self, name: str) -> ImageMessage | None:
        """Never: a frame through `ros2 topic echo` is megabytes of text a second."""
        raise ValueError(f"{name}: the ros2 CLI transport reads no camera frames (rclpy does)")

    def events_since(self, seq: int) -> list[RobotEvent]:
        return self.events.since(seq)

    def topic_stats(self) -> list[TopicStat]:
        return live_topic_stats(self.catalog.topics, self._streams, time.monotonic())

    def map_geometry(self):
        return self._map

    def read_map(self, timeout_s: float):
        if self._map is None and self._name("map") in self.catalog.topics:
            self._read_map()
        return self._map

    def _read_map(self) -> None:
        name = self._name("map")
        spec = self.catalog.topics[name]
        argv = ["topic", "echo", name, spec.type, "--once", "--full-length"]
        argv += ["--qos-durability", "transient_local", "--qos-reliability", "reliable"]
        run = self._run(argv, 30.0)
        doc = parse_document(run.out.split("\n---", 1)[0].splitlines(keepends=True))
        if doc is None:
            self.events.add("map", "warning", f"no {name} received: the map view follows the scan")
            return
        try:
            self._map = grid_from_message(doc)
        except (KeyError, TypeError, ValueError) as exc:
            self.events.add("map", "warning", f"{name} could not be read: {exc}")

    def wait_until_idle(self, timeout_s: float) -> str | None:
        def state() -> str | None:
            with self._lock:
                return (self._latest.get(self._name("status")) or {}).get("state")

        # a goal's client is followed until its last line is read (its outcome), not only
        # until its process exits: the follower drops it from the list then
        return live_robot.wait_until_idle(
            timeout_s,
            lost=lambda: self._lost_for(time.monotonic()) is not None,
            goals_running=lambda: bool(self._commands.goal_procs),
            state=state,
            outcome=lambda: self._commands.last_outcome,
        )

    # -- commands and the E-STOP (ros2cli/commands.py, ros2cli/estop.py) ------------------
    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        return self._commands.execute(checked, timeout)

    def cancel_goals(self) -> None:
        self._commands.cancel_goals()

    @property
    def e_stopped(self) -> bool:
        return self.inflight.held

    def estop(self) -> list[str]:
        return self._estop.estop()

    def settle_estop(self, timeout_s: float) -> list[str]:
        return self._estop.settle(timeout_s)

    def release_estop(self, *, robot: bool = True) -> list[str]:
        return self._estop.release(robot=robot)

    # -- teleop ---------------------------------------------------------------------------
    def drive(self, twist: dict) -> None:
        if self._teleop is None:
            raise BackendError("the robot has no /cmd_vel")
        job = self._teleop_held()
        with job.sending():
            self._teleop.drive(twist)
        if self._teleop_job is not job:  # it lapsed meanwhile: this key's publisher is new
            self._teleop_held()

    def _teleop_held(self) -> Job:
        with self._lock:
            if self._teleop_job is None:  # refused while the E-STOP holds
                self._teleop_job = self.inflight.start("teleop", self._halt_teleop)
            return self._teleop_job

    def _halt_teleop(self) -> None:
        with self._lock:
            self._teleop_job = None
        if self._teleop is not None:
            self._teleop.halt()

    def _teleop_lapsed(self) -> None:
        """Teleop's keys stopped and its publisher was stopped: nothing of it is in flight."""
        with self._lock:
            job, self._teleop_job = self._teleop_job, None
        if job is not None:
            job.done()
