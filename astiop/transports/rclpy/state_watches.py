"""The rclpy transport's watches of the robot's state topics: made when a publisher appears, and
/odom and a fleet robot's scans watched only while wanted."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any, Protocol

from astiop.ros2.catalog import Catalog
from astiop.ros2.roles import COMPRESSED_IMAGE, IMAGE
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


class RclpyStateWatchesHost(Protocol):
    """What `RclpyStateWatches` needs of the backend it is mixed into."""

    catalog: Catalog
    proc: RosProcess
    light: bool
    _watches: dict[str, TopicWatch]
    _watch_lock: threading.Lock
    _wanted: dict[str, float]
    _poke: threading.Event
    _closed: threading.Event
    _map_watch: TopicWatch | None

    def _name(self, role: str, default: str = "") -> str: ...

    def _on_message(self, name: str, msg: Any) -> None: ...

    def _on_map(self, name: str, msg: Any) -> None: ...


if TYPE_CHECKING:
    _Host = RclpyStateWatchesHost
else:
    _Host = object


class RclpyStateWatches(_Host):
    def _watch_state_topics(self) -> None:
        with self._watch_lock:
            self._watch_state_topics_locked()

    def _watch_state_topics_locked(self) -> None:
        if self._closed.is_set():
            return  # a refresh that outlived close(): no watch the process would keep
        map_name = self._name("map")
        names = self.catalog.state_topics() + ([map_name] if map_name else [])
        names += [n for n in self._wanted if n not in names and self._is_wanted(n)]
        for name in names:
            spec = self.catalog.topics.get(name)
            if spec is None or name in self._watches or (name == map_name and self._map_watch):
                continue
            if name == self._name("odometry") and not self._is_wanted(name):
                continue
            if spec.type in IMAGE_TYPES:
                if self.proc.node.get_publishers_info_by_topic(name):
                    w = image_watch(self.proc, name, spec.type)
                    self._watches = {**self._watches, **({name: w} if w else {})}
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
        spec = self.catalog.topics.get(name)
        if name == self._name("odometry") or (spec is not None and spec.type in IMAGE_TYPES):
            self._wanted[name] = time.monotonic() + WANTED_S
            if name not in self._watches:
                self._poke.set()

    def _is_wanted(self, name: str) -> bool:
        profile = self.catalog.profile
        spec = self.catalog.topics.get(name)
        if spec is not None and spec.type in IMAGE_TYPES:
            return time.monotonic() < self._wanted.get(name, 0.0)
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
            images = [n for n, w in self._watches.items() if w.type in IMAGE_TYPES]
            for name in [self._name("odometry"), *scans, *images]:
                w = self._watches.get(name)
                if w is not None and not self._is_wanted(name):
                    self._watches = {n: v for n, v in self._watches.items() if n != name}
                    w.close()
