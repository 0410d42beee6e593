"""The emulated robot's `ros2 topic` verbs: list, type, info, echo, hz, pub."""

from __future__ import annotations

import collections
import contextlib
import math
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import yaml

from astiop.robot_programs.emulated_cli.call import Call
from astiop.robot_programs.emulated_cli.verb_table import runs
from astiop.ros2.catalog import Catalog
from astiop.ros2.interfaces import InterfaceError, fill, python_repr
from astiop.ros2.printing import echo_yaml, list_text
from astiop.sim import messages as sm
from astiop.transports.base import BackendError
from astiop.transports.simulator.backend import SimBackend

HIDDEN_TOPICS = {
    "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
    "/rosout": "rcl_interfaces/msg/Log",
}


def listing(call: Call, names: dict[str, str], types: bool | None, count: bool | None) -> int:
    """A `... list` verb's lines: each name, its type with -t, the count alone with -c."""
    flags = {"show_types"} if types else set()
    call.out(list_text(list(names.items()), flags | ({"count_topics"} if count else set()))[0])
    return 0


class RobotTopics:
    """The topic verbs on the simulated robot: what it publishes, at its rates on its clock
    (`backend.sim`), and /cmd_vel driving it. `topics` is the robot's graph as `topic list`
    prints it; `catalog` says who publishes and subscribes each topic, and how often. It keeps
    each Twist received, with when it came (`cmd_vel_log`, for measurements)."""

    def __init__(self, backend: SimBackend, catalog: Catalog, topics: Callable[[], dict[str, str]]):
        self.backend = backend
        self.sim = backend.sim
        self.catalog = catalog
        self.topics = topics
        self.cmd_vel_log: collections.deque = collections.deque(maxlen=2000)
        self._twist_seq = 0
        self._map_msg = sm.occupancy_grid(self.sim.map)

    @runs("topic list")
    def _topic_list(self, call: Call, a: dict) -> int:
        return listing(call, self.topics(), a.get("show_types"), a.get("count_topics"))

    @runs("topic type")
    def _topic_type(self, call: Call, a: dict) -> int:
        t = self.topics().get(a["topic_name"])
        if t is None:  # nothing printed (ros2topic/verb/type.py)
            return 1
        call.out(t + "\n")
        return 0

    @runs("topic info")
    def _topic_info(self, call: Call, a: dict) -> int:
        name = a["topic_name"]
        t = self.topics().get(name)
        if t is None:
            call.err(f"Unknown topic '{name}'\n")
            return 1
        spec = self.catalog.topics.get(name)
        pubs = int(bool(spec.publisher)) if spec else 1
        subs = int(bool(spec.subscriber)) if spec else 0
        call.out(f"Type: {t}\nPublisher count: {pubs}\nSubscription count: {subs}\n")
        return 0

    def _message(self, name: str) -> dict:
        if name == "/map":
            return self._map_msg
        msg = self.backend.message(name)
        if name == "/diagnostics":  # rclpy prints a `byte` as a one-character string
            msg = {**msg, "status": [{**st, "level": chr(st["level"])} for st in msg["status"]]}
        return msg

    @runs("topic echo")
    def _topic_echo(self, call: Call, a: dict) -> int:
        name = a["topic_name"]
        t = self.topics().get(name)
        if t is None or name in HIDDEN_TOPICS:
            if a.get("message_type") is None:
                call.err(
                    f"WARNING: topic [{name}] does not appear to be published yet\n"
                    "Could not determine the type for the passed topic\n"
                )
                return 1
            call.wait(1e9)  # nobody publishes it: echo waits
        given = a.get("message_type")
        if given and t and given not in (t, t.replace("/msg/", "/")):
            call.err("The passed message type is invalid\n")  # rosidl cannot load it
            return 1
        truncate = None if a.get("full_length") else a.get("truncate_length", 128)
        deadline = time.monotonic() + a["timeout"] if a.get("timeout") else math.inf
        for msg in self._publications(name, call, deadline):
            call.out(echo_yaml(msg, a.get("no_arr", False), truncate, a.get("no_str", False)))
            if a.get("once"):
                return 0
        return 0

    def _publications(self, name: str, call: Call, deadline: float) -> Iterator[Any]:
        """Messages as the robot publishes them, at its rate, on its clock."""
        spec = self.catalog.topics.get(name)
        rate = spec.rate_hz if spec else 0.0
        if name in ("/tf_static", "/map"):
            yield self._message(name)
            call.wait(max(deadline - time.monotonic(), 0) if deadline < math.inf else 1e9)
            return
        if name == "/cmd_vel":
            seen = self._twist_seq
            while time.monotonic() < deadline:
                call.wait(0.01)
                if self._twist_seq != seen:
                    seen = self._twist_seq
                    yield self.backend.last_twist
            return
        period = 1.0 / rate

        def after(t: float) -> float:  # the next publication time (1e-9: floor(0.3/0.1) == 2)
            return (math.floor(t / period + 1e-9) + 1) * period

        next_t = after(self.sim.t)
        while time.monotonic() < deadline:
            call.wait(0.005)
            if self.sim.t >= next_t - 1e-9:
                next_t = after(self.sim.t)
                if name == "/plan" and self.sim.goal is None:
                    continue
                yield self._message(name)

    @runs("topic hz")
    def _topic_hz(self, call: Call, a: dict) -> int:
        name = a["topic_name"]
        spec = self.catalog.topics.get(name)
        if name not in self.topics():
            call.err(f"WARNING: topic [{name}] does not appear to be published yet\n")
            call.wait(1e9)
        stamps: list[float] = []
        last_print = time.monotonic()
        for _msg in self._publications(name, call, math.inf) if spec else ():
            stamps.append(time.monotonic())
            stamps = stamps[-a["window_size"] :]
            if time.monotonic() - last_print >= 1.0 and len(stamps) > 1:
                last_print = time.monotonic()
                d = np.diff(stamps)
                call.out(
                    f"average rate: {1.0 / d.mean():.3f}\n\tmin: {d.min():.3f}s max: {d.max():.3f}s std dev: {d.std():.5f}s window: {len(stamps)}\n"
                )
        call.wait(1e9)
        return 0

    @runs("topic pub")
    def _topic_pub(self, call: Call, a: dict) -> int:
        name, type_ = a["topic_name"], a["message_type"]
        text = a.get("stdin_values") if a.get("stdin") else a.get("values", "{}")
        try:
            values = yaml.safe_load(text or "")
        except yaml.YAMLError as exc:
            call.err(f"{exc}\n")
            return 1
        if not isinstance(values, dict):
            call.err("The passed value needs to be a dictionary in YAML format\n")
            return 1
        if name != "/cmd_vel" or type_ not in ("geometry_msgs/msg/Twist", "geometry_msgs/Twist"):
            call.err(
                f"the emulated robot only listens to /cmd_vel "
                f"(geometry_msgs/msg/Twist), not {name} ({type_})\n"
            )
            return 1
        try:
            twist = fill("geometry_msgs/msg/Twist", values)
        except InterfaceError as exc:
            call.err(f"Failed to populate field: {exc}\n")
            return 1
        times = 1 if a.get("once") else a.get("times", 0)
        call.out("publisher: beginning loop\n")
        count = 0
        while times == 0 or count < times:
            count += 1
            self._receive_twist(twist, times == 1)
            if count % max(a.get("print", 1), 1) == 0:
                call.out(
                    f"publishing #{count}: {python_repr('geometry_msgs/msg/Twist', twist)}\n\n"
                )
            if times and count >= times:
                break
            call.wait(1.0 / a["rate"])
        time.sleep(a.get("keep_alive", 0.1))
        return 0

    def _receive_twist(self, twist: dict, once: bool) -> None:
        self.cmd_vel_log.append({"mono": time.monotonic(), "twist": twist})
        self._twist_seq += 1
        self.backend.last_twist, self.backend.last_twist_t = twist, self.sim.t
        with contextlib.suppress(BackendError):  # an e-stopped or faulted base holds still
            self.backend.drive(twist)
