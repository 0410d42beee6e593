"""The rclpy transport's watches of the robot's state topics: made when a publisher appears, and
/odom and a fleet robot's scans watched only while wanted."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from astiop.ros2.roles import COMPRESSED_IMAGE, IMAGE
from astiop.transports.live_catalog import LiveGraph
from astiop.transports.rclpy.node import RosProcess
from astiop.transports.rclpy.watch import TopicWatch, image_watch, watch, watch_transforms
from astiop.transports.state import GOAL_STATUS, goal_status_topic

SCAN_TYPES = frozenset({"sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2"})
# A camera's frames are watched only while something shows them (the console's camera view)
IMAGE_TYPES = frozenset({IMAGE, COMPRESSED_IMAGE})
# Watched only while wanted: /odom at 50 Hz was most of the console's rclpy cost, and what the
# state takes from it, /robot_status (speed) and /robot_pose (pose) carry too. Wanted while this
# process drives, while the robot moves (its status says so), and while a reader (a recording)
# asks for its messages; always where the robot lacks /robot_pose or /robot_status.
WANTED_S = 2.0  # an on-demand topic stays watched this long after it was last wanted

OnMessage = Callable[[str, Any], None]  # (topic, message object)


class RclpyStateWatches:
    """The watches of the robot's state topics (`watches`, by name) and of its map. Made by
    `watch_state_topics` (the graph thread's, and the first read's); `poke` is set when the
    graph thread should make them now (a topic newly wanted)."""

    def __init__(
        self,
        proc: RosProcess,
        live: LiveGraph,
        closed: threading.Event,
        on_status: OnMessage,
        on_map: OnMessage,
    ):
        self.proc = proc
        self.live = live
        self._closed = closed
        self._on_status = on_status  # each /robot_status and goal status list, as it comes
        self._on_map = on_map
        self.watches: dict[str, TopicWatch] = {}  # replaced, never changed: read unlocked
        self.map_watch: TopicWatch | None = None
        self._lock = threading.Lock()  # watches made and dropped by one thread at a time
        self._wanted: dict[str, float] = {}  # an on-demand topic -> wanted until (monotonic)
        self.poke = threading.Event()  # the graph thread: subscribe what is wanted now
        self.light = False  # a fleet's robot watched for its row: no scan (watch_lightly)

    def watch_state_topics(self) -> None:
        with self._lock:
            self._watch_state_topics_locked()

    def _watch_state_topics_locked(self) -> None:
        if self._closed.is_set():
            return  # a refresh that outlived close(): no watch the process would keep
        catalog, name_of = self.live.catalog, self.live.name
        map_name = name_of("map")
        names = catalog.state_topics() + ([map_name] if map_name else [])
        names += [n for n in list(self._wanted) if n not in names and self._is_wanted(n)]
        for name in names:
            spec = catalog.topics.get(name)
            if spec is None or name in self.watches or (name == map_name and self.map_watch):
                continue
            if name == name_of("odometry") and not self._is_wanted(name):
                continue
            if spec.type in IMAGE_TYPES:
                if self.proc.node.get_publishers_info_by_topic(name):
                    image = image_watch(self.proc, name, spec.type)
                    self.watches = {**self.watches, **({name: image} if image else {})}
                continue
            if self._light_skips(name, spec.type):
                continue
            if not self.proc.node.get_publishers_info_by_topic(name):
                continue  # subscribed when a publisher appears, with its QoS
            if name == map_name:
                self.map_watch = watch(self.proc, name, spec.type, self._on_map)
                continue
            on_message = self._on_status if name == name_of("status") else None  # events
            w: TopicWatch | None
            if name in (name_of("transforms"), name_of("static_transforms")):
                static = name == name_of("static_transforms")
                w = watch_transforms(self.proc, name, spec.type, static)
            else:
                w = watch(self.proc, name, spec.type, on_message)
            if w is not None:  # a new dict: the sampler may be iterating the old one
                self.watches = {**self.watches, name: w}
        goals = goal_status_topic(catalog.profile)
        if (
            goals
            and goals not in self.watches
            and self.proc.node.get_publishers_info_by_topic(goals)
        ):
            w = watch(self.proc, goals, GOAL_STATUS, self._on_status)  # any client's goal's end
            if w is not None:
                self.watches = {**self.watches, goals: w}

    def watch_map(self, name: str, type_: str) -> None:
        """The map watched from now (latched: it comes with the subscription's first match)."""
        with self._lock:
            if self.map_watch is None and not self._closed.is_set():
                self.map_watch = watch(self.proc, name, type_, self._on_map)

    # -- topics watched on demand -------------------------------------------------------------
    def want(self, name: str) -> None:
        """Keep an on-demand topic watched for WANTED_S from now (the graph thread subscribes it:
        never the caller, who may be the executor's callback or a key press)."""
        spec = self.live.catalog.topics.get(name)
        if name == self.live.name("odometry") or (spec is not None and spec.type in IMAGE_TYPES):
            self._wanted[name] = time.monotonic() + WANTED_S
            if name not in self.watches:
                self.poke.set()

    def _is_wanted(self, name: str) -> bool:
        profile = self.live.catalog.profile
        spec = self.live.catalog.topics.get(name)
        if spec is not None and spec.type in IMAGE_TYPES:
            return time.monotonic() < self._wanted.get(name, 0.0)
        if profile and (profile.name("pose") == name or not profile.has("status")):
            return True  # the robot's pose or speed has no other source
        return time.monotonic() < self._wanted.get(name, 0.0)

    def watch_lightly(self, light: bool) -> None:
        self.light = light
        self.poke.set()  # subscribed, or dropped at the graph thread's next read

    def _light_skips(self, name: str, type_: str) -> bool:
        """A scan not subscribed for a fleet's robot watched for its row (unless wanted)."""
        return self.light and type_ in SCAN_TYPES and not self._is_wanted(name)

    def drop_unwanted(self) -> None:
        with self._lock:
            scans = [n for n, w in self.watches.items() if self._light_skips(n, w.type)]
            images = [n for n, w in self.watches.items() if w.type in IMAGE_TYPES]
            for name in [self.live.name("odometry"), *scans, *images]:
                w = self.watches.get(name)
                if w is not None and not self._is_wanted(name):
                    self.watches = {n: v for n, v in self.watches.items() if n != name}
                    w.close()

    def close(self) -> None:
        """Every watch closed; the graph thread woken to see the process closed."""
        self.poke.set()
        with self._lock:  # none is being made meanwhile
            for w in [*self.watches.values(), *([self.map_watch] if self.map_watch else [])]:
                w.close()
            self.watches, self.map_watch = {}, None
