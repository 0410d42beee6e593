"""ROS 2 in process through rclpy: live state by subscription, teleop and E-STOP by an in-process
publisher, every checked command executed here and printed as ros2cli prints it."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import current_distro
from astiop.ros2.message_objects import interface_class, to_dict, to_message
from astiop.ros2.profile import ProfileSpec
from astiop.ros2.render import velocity_message, zero_twist
from astiop.ros2.validation import CANCEL_SUFFIX
from astiop.transports import live_robot
from astiop.transports.base import BackendError, RobotBackend
from astiop.transports.event_log import Contact, EstopWork, EventLog
from astiop.transports.inflight import InFlight, Job
from astiop.transports.live_catalog import (
    CANCEL_GOAL,
    NAVIGATE,
    RELEASE,
    GraphLists,
    describe_graph,
    navigation_actions,
    stop_service_type,
)
from astiop.transports.live_robot import MOVING, without_finished_plan
from astiop.transports.rclpy.empty_calls import EmptyCalls
from astiop.transports.rclpy.graph import read_lists, read_params
from astiop.transports.rclpy.node import ros_process
from astiop.transports.rclpy.verbs import RclpyVerbs
from astiop.transports.rclpy.watch import TopicWatch, watch, watch_transforms
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

GRAPH_POLL_S = 1.0
DISCOVERY_S = 3.0  # at most this long for a new process's discovery to settle
SCAN_TYPES = frozenset({"sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2"})
SHARED_READ_S = 0.1  # a graph read this recent serves every gateway of the process
DISCOVERY_QUIET_S = 1.0  # no change in the graph for this long: discovery has settled
DISCOVERY_YOUNG_S = 10.0  # a process this young may not have discovered the whole robot
PARAMS_REFRESH_S = 30.0
SILENT_S = 3.0  # a state topic's last message older than this is no longer the robot's state
TELEOP_HZ = 10.0
LAPSE_S = 0.5
ESTOP_BURST_S = 1.0
# Watched only while wanted: /odom at 50 Hz was most of the console's rclpy cost, and what the
# state takes from it, /robot_status (speed) and /robot_pose (pose) carry too. Wanted while this
# process drives, while the robot moves (its status says so), and while a reader (a recording)
# asks for its messages; always where the robot lacks /robot_pose or /robot_status.
WANTED_S = 2.0  # an on-demand topic stays watched this long after it was last wanted
MOVING_SPEED = 0.005  # m/s: /robot_status's speed above this is a robot that moves


class RclpyBackend(RclpyVerbs, RobotBackend):
    name = "ros2"
    capabilities = frozenset({"commands", "teleop"})
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

    def control_channel(self, namespace: str):
        from astiop.transports.rclpy.control_topic import ControlTopic

        topic = ControlTopic(self.proc, namespace)
        topic.settle()
        return topic

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
        new = nodes if stale else [n for n in nodes if n not in self._params_of]
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

    def _watch_state_topics(self) -> None:
        with self._watch_lock:
            self._watch_state_topics_locked()

    def _watch_state_topics_locked(self) -> None:
        if self._closed.is_set():
            return  # a refresh that outlived close(): no watch the process would keep
        map_name = self._name("map")
        for name in self.catalog.state_topics() + ([map_name] if map_name else []):
            spec = self.catalog.topics.get(name)
            if spec is None or name in self._watches or (name == map_name and self._map_watch):
                continue
            if name == self._name("odometry") and not self._is_wanted(name):
                continue
            if self._light_skips(name, spec.type):
                continue
            if not self.proc.node.get_publishers_info_by_topic(name):
                continue  # subscribed when a publisher appears, with its QoS
            if name == map_name:
                self._map_watch = watch(self.proc, name, spec.type, self._on_map)
                continue
            on_message = self._on_message if name == self._name("status") else None  # events
            if name in (self._name("transforms"), self._name("static_transforms")):
                static = name == self._name("static_transforms")
                w = watch_transforms(self.proc, name, spec.type, static)
            else:
                w = watch(self.proc, name, spec.type, on_message)
            if w is not None:  # a new dict: the sampler may be iterating the old one
                self._watches = {**self._watches, name: w}
        goals = goal_status_topic(self.catalog.profile)
        if (
            goals
            and goals not in self._watches
            and self.proc.node.get_publishers_info_by_topic(goals)
        ):
            w = watch(self.proc, goals, GOAL_STATUS)
            if w is not None:
                self._watches = {**self._watches, goals: w}

    # -- topics watched on demand -------------------------------------------------------------
    def _want(self, name: str) -> None:
        """Keep an on-demand topic watched for WANTED_S from now (the graph thread subscribes it:
        never the caller, who may be the executor's callback or a key press)."""
        if name == self._name("odometry"):
            self._wanted[name] = time.monotonic() + WANTED_S
            if name not in self._watches:
                self._poke.set()

    def _is_wanted(self, name: str) -> bool:
        profile = self.catalog.profile
        if profile and (profile.name("pose") == name or not profile.has("status")):
            return True  # the robot's pose or speed has no other source
        return time.monotonic() < self._wanted.get(name, 0.0)

    def watch_lightly(self, light: bool) -> None:
        self.light = light
        self._poke.set()  # subscribed, or dropped at the graph thread's next read

    def _light_skips(self, name: str, type_: str) -> bool:
        """A scan not subscribed for a fleet's robot watched for its row (unless wanted)."""
        return self.light and type_ in SCAN_TYPES and not self._is_wanted(name)

    def _drop_unwanted(self) -> None:
        with self._watch_lock:
            scans = [n for n, w in self._watches.items() if self._light_skips(n, w.type)]
            for name in [self._name("odometry"), *scans]:
                w = self._watches.get(name)
                if w is not None and not self._is_wanted(name):
                    self._watches = {n: v for n, v in self._watches.items() if n != name}
                    w.close()

    def close(self) -> None:
        self._closed.set()
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

    # -- teleop and the E-STOP ------------------------------------------------------------------
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

    @property
    def e_stopped(self) -> bool:
        return self.inflight.held

    def zero_now(self) -> None:
        if self._name("velocity_command"):
            self._send_twist(zero_twist())

    def estop(self) -> list[str]:
        """Everything in flight ended first (timed publishes, goals, teleop), then the zero Twist
        now and /stop called, neither waiting on the other; failures that come later arrive as
        events (`settle_estop`)."""
        failures = self.inflight.stop_all()
        self._estop.begin()
        try:
            self.zero_now()  # matched already in a running console
            self._estop.start(self._zero_burst, "estop-zero")
        except Exception as exc:  # noqa: BLE001 - /stop and the cancels go out regardless
            failures.append(f"{exc}: no zero Twist was sent")
        # The graph this process holds may be partial (a new process's E-STOP does not wait
        # for it): a stop service it shows is called; one it does not show is still tried, and
        # only a robot seen without it has none (said, not failed). Then every NavigateToPose
        # goal on the robot is cancelled, another client's too (a TurtleBot3 has no /stop).
        stop = self._name("stop")
        stop_type = stop_service_type(self.catalog)
        if stop:
            self._estop.start(lambda: self._calls.call(stop, stop_type, "E-STOP"), "estop-stop")
        else:
            name = self._fixed.namespace + "/stop"
            self._estop.start(
                lambda: self._calls.call_if_served(name, stop_type, "E-STOP", self._base_seen),
                "estop-stop",
            )
            actions = navigation_actions(self.catalog, self._fixed.namespace) or [
                self._fixed.namespace + NAVIGATE
            ]
            for action in actions:
                self._estop.start(lambda a=action: self._cancel_every_goal(a), "estop-cancel")
        self._estop.said(failures)
        return failures

    def _cancel_every_goal(self, action: str) -> None:
        """A CancelGoal with a zero goal id and a zero stamp cancels every goal of the action
        server (ros2/rcl_interfaces action_msgs/srv/CancelGoal.srv, humble and jazzy)."""
        name, what = f"{action}{CANCEL_SUFFIX}", "E-STOP cancel"
        if action in self.catalog.actions:
            self._calls.call(name, CANCEL_GOAL, what)
        else:  # not on the graph this process holds (yet)
            self._calls.call_if_served(name, CANCEL_GOAL, what, self._base_seen)

    def _base_seen(self) -> bool:
        """The robot's base is on the graph: its velocity command has a subscriber."""
        velocity = self._name("velocity_command", "/cmd_vel")
        return bool(self.proc.node.get_subscriptions_info_by_topic(velocity))

    def _zero_burst(self) -> None:
        """A zero Twist at 10 Hz for a second from when the base listens (in a new process,
        discovery may take a moment: the first one may have found no one)."""
        try:
            deadline = time.monotonic() + self.timeout_s
            while True:
                try:
                    pub, _cls, _type = self._publisher()
                    break
                except BackendError:  # not discovered yet
                    if time.monotonic() > deadline:
                        velocity = self._name("velocity_command", "/cmd_vel")
                        raise BackendError(
                            f"no {velocity} on the robot's graph in {self.timeout_s:g} s"
                        ) from None
                    time.sleep(0.01)
            while pub.get_subscription_count() < 1:
                if time.monotonic() > deadline:
                    raise BackendError(
                        f"nothing subscribed to {pub.topic_name} in {self.timeout_s:g} s"
                    )
                time.sleep(0.01)
            end = time.monotonic() + ESTOP_BURST_S
            while time.monotonic() < end and self.inflight.held and not self._closed.is_set():
                self._send_twist(zero_twist())
                time.sleep(1.0 / TELEOP_HZ)
        except Exception as exc:  # noqa: BLE001 - said, never raised: /stop goes on
            self.events.add("estop", "error", f"E-STOP zero Twist: {exc}")

    def settle_estop(self, timeout_s: float) -> list[str]:
        # /stop waits for its server, then for the answer: each may take the timeout (the
        # burst ends sooner: its timeout and a second)
        return self._estop.settle(2 * timeout_s)

    def release_estop(self, *, robot: bool = True) -> list[str]:
        self.inflight.release()
        name = self._name("release", RELEASE)  # under the robot's namespace
        spec = self.catalog.services.get(name)
        if spec is None or not robot:
            return []
        seq = self.events.seq  # a robot that latches its own stop lets go too
        self._calls.call(name, spec.type, "release")
        return [e.message for e in self.events.since(seq) if e.kind == "estop"]
