"""ROS 2 in process through rclpy: live state by subscription, teleop and E-STOP by an in-process
publisher, every checked command executed here and printed as ros2cli prints it."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterable
from typing import Any

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import current_distro
from astiop.ros2.message_objects import to_dict
from astiop.ros2.profile import ProfileSpec
from astiop.ros2.validation import Checked
from astiop.transports import live_robot
from astiop.transports.base import RobotTransport
from astiop.transports.event_log import Contact, EventLog
from astiop.transports.goal_ends import GoalEnds, status_list
from astiop.transports.images import ImageMessage, image_message
from astiop.transports.inflight import InFlight
from astiop.transports.live_catalog import GraphLists, LiveGraph, describe_graph
from astiop.transports.live_robot import MOVING, without_finished_plan
from astiop.transports.rclpy.estop import RclpyEstop
from astiop.transports.rclpy.graph import read_lists, read_params
from astiop.transports.rclpy.node import NODE_PREFIX, ros_process
from astiop.transports.rclpy.state_watches import IMAGE_TYPES, RclpyStateWatches
from astiop.transports.rclpy.teleop import RclpyTeleop
from astiop.transports.rclpy.verbs import RclpyVerbs
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


class RclpyBackend(RobotTransport):
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
        self._refresh_lock = threading.Lock()
        self._map: OccupancyGrid | None = None
        self.inflight = InFlight()
        self._closed = threading.Event()
        self.t0 = time.monotonic()
        self.events = EventLog(self.t0)
        self._contact = Contact(self.events)
        lists = self._discover(DISCOVERY_S if discover else 0.0)
        self._params: list[tuple[str, str]] = []  # read by start(), or when a command needs them
        self._params_of: dict[str, list[tuple[str, str]]] = {}  # node -> its parameters
        catalog = describe_graph({**lists, "param": self._params}, self._fixed)
        self._live = LiveGraph(catalog, self._fixed, lists)
        self.refreshed_at = 0.0  # the parameters are not read yet
        # its parts, each handed what it uses (rclpy/state_watches.py, teleop.py, estop.py,
        # verbs.py)
        self._watching = RclpyStateWatches(
            self.proc, self._live, self._closed, self._on_message, self._on_map
        )
        self._teleop = RclpyTeleop(
            self.proc, self._live, self.inflight, self.events, self._closed, self._watching.want
        )
        self._estop = RclpyEstop(
            self.proc, self._live, self.inflight, self.events, timeout_s, self._teleop,
            self._closed,
        )  # fmt: skip
        self._goal_ends = GoalEnds(self.events)  # any client's goals, as the server lists them
        self._verbs = RclpyVerbs(
            self.proc, self._live, self.inflight, self.events, self._watching, self._teleop,
            self._goal_ends,
        )  # fmt: skip

    def _discover(self, settle_s: float) -> GraphLists:
        """Discovery is under way in a new process: read until the graph stops growing (Fast
        DDS announces a participant's endpoints in rounds, so a pause is not the end). A robot
        under a namespace (one of a fleet, each in its own process) is waited for until a name
        of its own is seen, up to the transport's timeout: on a loaded machine one participant
        may be discovered seconds after another."""
        ns = self._fixed.namespace.rstrip("/")
        t0 = time.monotonic()
        deadline = t0 + settle_s
        longest = t0 + self.timeout_s if ns and settle_s > 0 else deadline

        def its_own(lists: GraphLists) -> bool:
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
    @property
    def catalog(self) -> Catalog:
        return self._live.catalog

    @catalog.setter
    def catalog(self, catalog: Catalog) -> None:
        self._live.catalog = catalog

    def _name(self, role: str, default: str = "") -> str:
        return self._live.name(role, default)

    @property
    def robot_nodes(self) -> list[str]:
        """The nodes discovered on the robot's domain (not this process's own)."""
        return [n for n, _ in self._live.lists["node"]]

    def robot_present(self) -> bool | None:
        names = self.proc.node.get_node_names_and_namespaces()
        ns = self._fixed.namespace.rstrip("/")
        return any(
            not name.startswith(NODE_PREFIX) and (not ns or space.startswith(ns))
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
        if lists != self._live.lists or params != self._params:  # else as described
            self._params, self._live.lists = params, lists
            self.catalog = describe_graph({**lists, "param": params}, self._fixed)
        self.refreshed_at = time.monotonic()
        self._watching.watch_state_topics()
        return True

    def _graph_loop(self) -> None:
        """The graph read each second; a wanted topic subscribed as soon as it is wanted."""
        next_read = time.monotonic() + GRAPH_POLL_S
        while not self._closed.is_set():
            poke = self._watching.poke
            poke.wait(max(0.0, next_read - time.monotonic()))
            if self._closed.is_set():
                return
            try:
                if poke.is_set():
                    poke.clear()
                    self._watching.watch_state_topics()
                if time.monotonic() >= next_read:
                    next_read = time.monotonic() + GRAPH_POLL_S
                    lists = read_lists(self.proc, max_age_s=GRAPH_POLL_S / 2)
                    if lists != self._live.lists:
                        with self._refresh_lock:
                            self._refresh(lists=lists)
                    self._watching.drop_unwanted()
                    self._lost_for(time.monotonic())
            except Exception as exc:  # noqa: BLE001 - the loop must outlive one bad read
                self.events.add("graph", "warning", f"reading the robot's graph failed: {exc}")

    def _lost_for(self, now: float) -> float | None:
        """Seconds since the robot was last heard, when it is lost (said once, as is its
        return)."""
        return self._contact.check([w.age(now) for w in self._watching.watches.values()])

    # -- lifecycle ---------------------------------------------------------------------------
    def start(self) -> None:
        if self._name("velocity_command"):
            self._teleop.publisher()  # matched now: the first key and the E-STOP do not wait
        self._watching.watch_state_topics()
        threading.Thread(target=self._graph_loop, name="rclpy-graph", daemon=True).start()
        threading.Thread(target=self._first_refresh, name="rclpy-params", daemon=True).start()
        threading.Thread(target=self._teleop.loop, name="rclpy-teleop", daemon=True).start()

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
        self._estop.close()
        self._watching.close()
        self._verbs.cancel_goals()  # as ros2cli's send_goal does on the way out
        self._teleop.close()

    # -- live state --------------------------------------------------------------------------
    def _on_message(self, name: str, msg: Any) -> None:
        if name == goal_status_topic(self.catalog.profile):
            self._goal_ends.listed(status_list(msg))
        elif name == self._name("status"):
            self.events.status(msg.state, msg.fault)
            if msg.state in MOVING or getattr(msg, "speed", 0.0) > MOVING_SPEED:
                # its velocity is worth its cost while the robot moves
                self._watching.want(self._name("odometry"))

    def read_map(self, timeout_s: float) -> OccupancyGrid | None:
        name = self._name("map")
        spec = self.catalog.topics.get(name) if name else None
        if spec is not None:
            self._watching.watch_map(name, spec.type)
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
        for name, w in self._watching.watches.items():
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
        if goals in self._watching.watches and goals not in messages:
            messages[goals] = {"status_list": []}  # its server is up and has had no goal
        messages = without_finished_plan(messages, profile)
        seq = self.events.seq
        state = from_messages(
            now - self.t0, messages, e_stopped=self.inflight.held, event_seq=seq, profile=profile
        )
        return state.with_lost(self._lost_for(now))

    def messages(self, names: Iterable[str]) -> dict[str, dict[str, Any]]:
        out = {}
        for n in names:
            self._watching.want(n)  # a reader (a recording) keeps asking: it stays watched
            w = self._watching.watches.get(n)
            msg = w.latest() if w else None
            if msg is not None:
                out[n] = msg
        return out

    def message_times(self, names: Iterable[str]) -> dict[str, float]:
        out = {}
        for n in names:
            self._watching.want(n)
            w = self._watching.watches.get(n)
            received = w.received() if w else None
            if received is not None:
                out[n] = received - self.t0
        return out

    def image(self, name: str) -> ImageMessage | None:
        """A camera's latest frame as it came (no dict of its pixels); watched while asked."""
        self._watching.want(name)
        w = self._watching.watches.get(name)
        received = w.received() if w else None
        if w is None or received is None:
            return None
        return image_message(name, w.latest_object(), received - self.t0)

    def events_since(self, seq: int) -> list[RobotEvent]:
        return self.events.since(seq)

    def topic_stats(self) -> list[TopicStat]:
        w = self._watching.map_watch
        map_watch = {self._name("map", "/map"): w} if w else {}
        watches = {**self._watching.watches, **map_watch}
        return live_topic_stats(self.catalog.topics, watches, time.monotonic())

    def map_geometry(self) -> OccupancyGrid | None:
        return self._map

    def wait_until_idle(self, timeout_s: float) -> str | None:
        def state() -> str | None:
            status = self._watching.watches.get(self._name("status"))
            return (status.latest() or {}).get("state") if status else None

        return live_robot.wait_until_idle(
            timeout_s,
            lost=lambda: self._lost_for(time.monotonic()) is not None,
            goals_running=lambda: bool(self._verbs.goals),
            state=state,
            outcome=lambda: self._verbs.last_outcome,
        )

    # -- commands, teleop and the E-STOP (rclpy/verbs.py, teleop.py, estop.py) -------------
    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        return self._verbs.execute(checked, timeout)

    def cancel_goals(self) -> None:
        self._verbs.cancel_goals()

    def drive(self, twist: dict) -> None:
        self._teleop.drive(twist)

    def zero_now(self) -> None:
        self._teleop.zero_now()

    def watch_lightly(self, light: bool) -> None:
        self._watching.watch_lightly(light)

    @property
    def e_stopped(self) -> bool:
        return self.inflight.held

    def estop(self) -> list[str]:
        return self._estop.estop()

    def warm_estop(self) -> None:
        self._estop.warm()

    def settle_estop(self, timeout_s: float) -> list[str]:
        return self._estop.settle(timeout_s)

    def release_estop(self, *, robot: bool = True) -> list[str]:
        return self._estop.release(robot=robot)
