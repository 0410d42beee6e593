"""ROS 2 in process through rclpy: live state by subscription, teleop and E-STOP by an in-process
publisher, every checked command executed here and printed as ros2cli prints it."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import current_distro
from astiop.ros2.message_objects import to_dict
from astiop.ros2.profile import ProfileSpec
from astiop.transports import live_robot
from astiop.transports.base import RobotBackend
from astiop.transports.event_log import Contact, EstopWork, EventLog
from astiop.transports.images import ImageMessage, image_message
from astiop.transports.inflight import InFlight, Job
from astiop.transports.live_catalog import GraphLists, describe_graph
from astiop.transports.live_robot import MOVING, without_finished_plan
from astiop.transports.rclpy.empty_calls import EmptyCalls
from astiop.transports.rclpy.estop import RclpyEstop
from astiop.transports.rclpy.graph import read_lists, read_params
from astiop.transports.rclpy.lock_hold import LockHold
from astiop.transports.rclpy.node import ros_process
from astiop.transports.rclpy.state_watches import IMAGE_TYPES, RclpyStateWatches
from astiop.transports.rclpy.teleop import RclpyTeleop
from astiop.transports.rclpy.verbs import RclpyVerbs
from astiop.transports.rclpy.watch import TopicWatch, watch
from astiop.transports.state import (
    OccupancyGrid,
    RobotEvent,
    RobotState,
    TopicStat,
    from_messages,
    goal_status_topic,
    grid_from_message,
    live_topic_stats,
)

GRAPH_POLL_S = 1.0
DISCOVERY_S = 3.0  # at most this long for a new process's discovery to settle
SHARED_READ_S = 0.1  # a graph read this recent serves every gateway of the process
DISCOVERY_QUIET_S = 1.0  # no change in the graph for this long: discovery has settled
DISCOVERY_YOUNG_S = 10.0  # a process this young may not have discovered the whole robot
PARAMS_REFRESH_S = 30.0
SILENT_S = 3.0  # a state topic's last message older than this is no longer the robot's state
MOVING_SPEED = 0.005  # m/s: /robot_status's speed above this is a robot that moves


class RclpyBackend(RclpyEstop, RclpyTeleop, RclpyStateWatches, RclpyVerbs, RobotBackend):
    name = "ros2"
    refresh_every_s = 0.0  # the graph is this process's discovery cache: reading it is free

    def __init__(
        self, timeout_s: float = 10.0, *, discover: bool = True, fixed: ProfileSpec | None = None
    ):
        self.timeout_s = timeout_s
        self._fixed = fixed or ProfileSpec()  # what the operator fixed: a file, a namespace
        self.distro = current_distro()
        self.proc = ros_process()
        self.label = f"ros2 via rclpy, {self.distro}, domain {self.proc.domain_id}"
        self._lock = threading.Lock()
        self._refresh_lock = threading.Lock()
        self._watches: dict[str, TopicWatch] = {}
        self._watch_lock = threading.Lock()  # watches made and dropped by one thread at a time
        self._wanted: dict[str, float] = {}  # an on-demand topic -> wanted until (monotonic)
        self._poke = threading.Event()  # the graph thread: subscribe what is wanted now
        self._holding = threading.Event()  # teleop holds a velocity: the teleop loop runs
        self._map_watch: TopicWatch | None = None
        self._map: OccupancyGrid | None = None
        self._goals: list[Any] = []  # goal handles this process sent and that have not ended
        self._last_outcome: str | None = None
        self.inflight = InFlight()
        self._teleop_job: Job | None = None  # while teleop holds a velocity
        self._closed = threading.Event()
        self._cmd_vel: tuple[Any, Any, str] | None = None  # publisher, class, type
        self._hold: dict | None = None
        self.light = False  # a fleet's robot watched for its row: no scan (watch_lightly)
        self._hold_until = 0.0
        self.t0 = time.monotonic()
        self.events = EventLog(self.t0)
        self._estop = EstopWork(self.events)
        self._calls = EmptyCalls(self.proc, self.events, timeout_s)
        self._lock_hold = LockHold(self.proc, lambda: self._name("estop_lock"), self.events)
        self._contact = Contact(self.events)
        self._lists = self._discover(DISCOVERY_S if discover else 0.0)
        self._params: list[tuple[str, str]] = []  # read by start(), or when a command needs them
        self._params_of: dict[str, list[tuple[str, str]]] = {}  # node -> its parameters
        self.catalog: Catalog = describe_graph({**self._lists, "param": self._params}, self._fixed)
        self.refreshed_at = 0.0  # the parameters are not read yet

    def _discover(self, settle_s: float) -> dict:
        """Discovery is under way in a new process: read until the graph stops growing (Fast
        DDS announces a participant's endpoints in rounds, so a pause is not the end). A robot
        under a namespace (one of a fleet, each in its own process) is waited for until a name
        of its own is seen, up to the transport's timeout: on a loaded machine one participant
        may be discovered seconds after another."""
        ns = self._fixed.namespace.rstrip("/")
        t0 = time.monotonic()
        deadline = t0 + settle_s
        longest = t0 + self.timeout_s if ns and settle_s > 0 else deadline

        def its_own(lists: dict) -> bool:
            return not ns or any(n.startswith(ns + "/") for n, _ in lists["topic"])

        # a read this recent is shared: a fleet's robots, opened at once, read one graph
        lists, stable_since = read_lists(self.proc, SHARED_READ_S), time.monotonic()
        while time.monotonic() < (deadline if its_own(lists) else longest):
            time.sleep(0.1)
            now = read_lists(self.proc, SHARED_READ_S)
            if now != lists:
                lists, stable_since = now, time.monotonic()
            elif (
                lists["node"]
                and its_own(lists)
                and time.monotonic() - stable_since > DISCOVERY_QUIET_S
            ):
                break
        return lists

    # -- the live graph --------------------------------------------------------------------
    def _name(self, role: str, default: str = "") -> str:
        """The robot's name for `role` (its profile); before the graph is read, `default` under
        the robot's namespace ("" for a role without a conventional name)."""
        name = self.catalog.profile.name(role) if self.catalog.profile else None
        return name or (self._fixed.namespace + default if default else "")

    @property
    def robot_nodes(self) -> list[str]:
        """The nodes discovered on the robot's domain (not this process's own)."""
        return [n for n, _ in self._lists["node"]]

    def robot_present(self) -> bool | None:
        names = self.proc.node.get_node_names_and_namespaces()
        ns = self._fixed.namespace.rstrip("/")
        return any(
            not name.startswith("astiop_") and (not ns or space.startswith(ns))
            for name, space in names
        )

    def control_channel(self, namespace: str):
        from astiop.transports.rclpy.control_topic import ControlTopic

        topic = ControlTopic(self.proc, namespace)
        topic.settle()
        return topic

    def estop_channel(self, namespace: str, on_word):
        from astiop.transports.rclpy.control_topic import ESTOP, ControlTopic

        return ControlTopic(self.proc, namespace, ESTOP, on_word)

    def discovering(self) -> bool:
        return time.monotonic() - self.t0 < DISCOVERY_YOUNG_S

    def refresh(self, settle: bool = True) -> bool:
        """Read the graph again, and the parameters when the nodes changed or 30 s passed;
        in a young process, until discovery settles (`settle=False`: as it is now)."""
        with self._refresh_lock:
            return self._refresh(settle)

    def _refresh(self, settle: bool = True, lists: GraphLists | None = None) -> bool:
        """`lists`: the graph just read by the caller (not read again)."""
        young = time.monotonic() - self.t0 < DISCOVERY_YOUNG_S  # discovery may still be going
        waits = young and settle
        if lists is None:
            lists = self._discover(DISCOVERY_QUIET_S * 3) if waits else read_lists(self.proc)
        # parameters of the nodes that serve them (other astiop processes do not), read for a
        # node when it appears, and for all of them every 30 s
        served = {n for n, _ in lists["service"]}
        ns = self._fixed.namespace  # a fleet's robot: its own nodes', not every robot's
        nodes = [
            n for n, _ in lists["node"]
            if f"{n}/list_parameters" in served and self.params_wanted
            and (not ns or n.startswith(ns + "/"))
        ]  # fmt: skip
        stale = time.monotonic() - self.refreshed_at > PARAMS_REFRESH_S
        # a node read before its parameter services answered listed none: read it again
        new = nodes if stale else [n for n in nodes if not self._params_of.get(n)]
        if new:
            read = read_params(self.proc, new, min(self.timeout_s, 2.0))
            for node in new:
                self._params_of[node] = [p for p in read if p[0].split(" ", 1)[0] == node]
        self._params_of = {n: ps for n, ps in self._params_of.items() if n in nodes}
        params = sorted(p for ps in self._params_of.values() for p in ps)
        if lists != self._lists or params != self._params:  # else the catalog is as described
            self._params, self._lists = params, lists
            self.catalog = describe_graph({**lists, "param": params}, self._fixed)
        self.refreshed_at = time.monotonic()
        self._watch_state_topics()
        return True

    def _graph_loop(self) -> None:
        """The graph read each second; a wanted topic subscribed as soon as it is wanted."""
        next_read = time.monotonic() + GRAPH_POLL_S
        while not self._closed.is_set():
            self._poke.wait(max(0.0, next_read - time.monotonic()))
            if self._closed.is_set():
                return
            try:
                if self._poke.is_set():
                    self._poke.clear()
                    self._watch_state_topics()
                if time.monotonic() >= next_read:
                    next_read = time.monotonic() + GRAPH_POLL_S
                    lists = read_lists(self.proc, max_age_s=GRAPH_POLL_S / 2)
                    if lists != self._lists:
                        with self._refresh_lock:
                            self._refresh(lists=lists)
                    self._drop_unwanted()
                    self._lost_for(time.monotonic())
            except Exception as exc:  # noqa: BLE001 - the loop must outlive one bad read
                self.events.add("graph", "warning", f"reading the robot's graph failed: {exc}")

    def _lost_for(self, now: float) -> float | None:
        """Seconds since the robot was last heard, when it is lost (said once, as is its
        return)."""
        return self._contact.check([w.age(now) for w in self._watches.values()])

    # -- lifecycle ---------------------------------------------------------------------------
    def start(self) -> None:
        if self._name("velocity_command"):
            self._publisher()  # matched now, so the first key and the E-STOP do not wait for it
        self._watch_state_topics()
        threading.Thread(target=self._graph_loop, name="rclpy-graph", daemon=True).start()
        threading.Thread(target=self._first_refresh, name="rclpy-params", daemon=True).start()
        threading.Thread(target=self._teleop_loop, name="rclpy-teleop", daemon=True).start()

    def _first_refresh(self) -> None:
        """The robot's parameters read in the background; a backend closed meanwhile (a short
        command: `astiop fleet list`) ends it, said by nothing."""
        try:
            self.refresh()
        except Exception:
            if not self._closed.is_set():
                raise

    def close(self) -> None:
        self._closed.set()
        self._lock_hold.stop()
        self._poke.set()
        self._holding.set()
        with self._watch_lock:  # none is being made meanwhile
            for w in [*self._watches.values(), *([self._map_watch] if self._map_watch else [])]:
                w.close()
            self._watches, self._map_watch = {}, None
        for handle in list(self._goals):
            handle.cancel_goal_async()  # as ros2cli's send_goal does on the way out
        if self._cmd_vel is not None:
            self.proc.node.destroy_publisher(self._cmd_vel[0])
            self._cmd_vel = None

    # -- live state --------------------------------------------------------------------------
    def _on_message(self, name: str, msg: Any) -> None:
        if name == self._name("status"):
            self.events.status(msg.state, msg.fault)
            if msg.state in MOVING or getattr(msg, "speed", 0.0) > MOVING_SPEED:
                self._want(
                    self._name("odometry")
                )  # its velocity is worth its cost while the robot moves

    def read_map(self, timeout_s: float):
        name = self._name("map")
        spec = self.catalog.topics.get(name) if name else None
        with self._watch_lock:
            if spec is not None and self._map_watch is None and not self._closed.is_set():
                self._map_watch = watch(self.proc, name, spec.type, self._on_map)
        deadline = time.monotonic() + timeout_s
        while self._map is None and spec is not None and time.monotonic() < deadline:
            time.sleep(0.05)  # latched: it comes with the subscription's first match
        return self._map

    def _on_map(self, name: str, msg: Any) -> None:
        try:
            self._map = grid_from_message(to_dict(msg))
        except (KeyError, TypeError, ValueError) as exc:
            self.events.add("map", "warning", f"{name} could not be read: {exc}")

    def _fresh(self, now: float) -> dict[str, dict[str, Any]]:
        """The latest message of each state topic that is not stale: older than three of its
        topic's periods (at least SILENT_S), it is no longer the robot's state."""
        out = {}
        for name, w in self._watches.items():
            spec = self.catalog.topics.get(name)
            if w.type in IMAGE_TYPES:
                continue  # no state is made of a frame: never decoded here
            period = 1.0 / spec.rate_hz if spec and spec.rate_hz else math.inf
            if w.age(now) <= max(3 * period, SILENT_S):
                msg = w.latest()
                if msg is not None:
                    out[name] = msg
        return out

    def robot_time(self) -> float:
        return self.proc.node.get_clock().now().nanoseconds * 1e-9

    def state(self) -> RobotState:
        now = time.monotonic()
        messages = self._fresh(now)
        profile = self.catalog.profile
        goals = goal_status_topic(profile)
        if goals in self._watches and goals not in messages:
            messages[goals] = {"status_list": []}  # its server is up and has had no goal
        messages = without_finished_plan(messages, profile)
        seq = self.events.seq
        state = from_messages(
            now - self.t0, messages, e_stopped=self.inflight.held, event_seq=seq, profile=profile
        )
        return state.with_lost(self._lost_for(now))

    def messages(self, names) -> dict[str, dict[str, Any]]:
        out = {}
        for n in names:
            self._want(n)  # a reader (a recording) keeps asking: it stays watched
            w = self._watches.get(n)
            msg = w.latest() if w else None
            if msg is not None:
                out[n] = msg
        return out

    def message_times(self, names) -> dict[str, float]:
        out = {}
        for n in names:
            self._want(n)
            w = self._watches.get(n)
            received = w.received() if w else None
            if received is not None:
                out[n] = received - self.t0
        return out

    def image(self, name: str) -> ImageMessage | None:
        """A camera's latest frame as it came (no dict of its pixels); watched while asked."""
        self._want(name)
        w = self._watches.get(name)
        received = w.received() if w else None
        if w is None or received is None:
            return None
        return image_message(name, w.latest_object(), received - self.t0)

    def events_since(self, seq: int) -> list[RobotEvent]:
        return self.events.since(seq)

    def topic_stats(self) -> list[TopicStat]:
        map_watch = {self._name("map", "/map"): self._map_watch} if self._map_watch else {}
        watches = {**self._watches, **map_watch}
        return live_topic_stats(self.catalog.topics, watches, time.monotonic())

    def map_geometry(self):
        return self._map

    def wait_until_idle(self, timeout_s: float) -> str | None:
        def state() -> str | None:
            status = self._watches.get(self._name("status"))
            return (status.latest() or {}).get("state") if status else None

        return live_robot.wait_until_idle(
            timeout_s,
            lost=lambda: self._lost_for(time.monotonic()) is not None,
            goals_running=lambda: bool(self._goals),
            state=state,
            outcome=lambda: self._last_outcome,
        )
