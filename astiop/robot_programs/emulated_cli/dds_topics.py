"""`ros2 topic echo|hz|pub` over real DDS, as ros2topic/verb/{echo,hz,pub}.py do them (humble
and jazzy): echo's QoS matched to the topic's publishers unless a --qos-* option is given, pub
waiting for a subscriber when it publishes a counted number of messages."""

from __future__ import annotations

import math
import queue
import time
from typing import Any

import yaml
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSPresetProfiles,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)

from astiop.robot_programs.emulated_cli.call import Call
from astiop.robot_programs.emulated_cli.dds_fields import load_class, set_message_fields
from astiop.robot_programs.emulated_cli.dds_query import DdsGraph
from astiop.robot_programs.emulated_cli.verb_table import runs
from astiop.ros2.message_objects import plain
from astiop.ros2.printing import echo_yaml

QOS_FLAGS = ("qos_reliability", "qos_durability", "qos_depth", "qos_history", "qos_liveliness",
             "qos_liveliness_lease_duration_seconds")  # fmt: skip
UNSUPPORTED_ECHO = ("csv", "filter_expr", "raw", "flow_style", "include_message_info")


def qos_from(a: dict, default: str) -> QoSProfile:
    """The preset named by --qos-profile, with the --qos-* options over it (ros2topic/api
    qos_profile_from_short_keys), as a copy: the presets are shared."""
    p = QoSPresetProfiles.get_from_short_key(a.get("qos_profile") or default)
    profile = QoSProfile(
        history=p.history, depth=p.depth, reliability=p.reliability, durability=p.durability
    )
    if a.get("qos_reliability"):
        profile.reliability = ReliabilityPolicy.get_from_short_key(a["qos_reliability"])
    if a.get("qos_durability"):
        profile.durability = DurabilityPolicy.get_from_short_key(a["qos_durability"])
    if a.get("qos_history"):
        profile.history = HistoryPolicy.get_from_short_key(a["qos_history"])
    if a.get("qos_depth") is not None:
        profile.depth = a["qos_depth"]
    return profile


class DdsTopics:
    """`ros2 topic echo|hz|bw|pub` on one rclpy node: each call's subscription or publisher is
    its own, destroyed when the call ends. `graph` is the node's view of the graph; `distro`
    decides how pub fills a message (`auto` and `now` stamps: not on humble)."""

    def __init__(self, node: Any, graph: DdsGraph, distro: str):
        self.node = node
        self.graph = graph
        self.distro = distro

    def _echo_qos(self, call: Call, a: dict) -> QoSProfile:
        if any(a.get(k) is not None for k in QOS_FLAGS):
            return qos_from(a, "sensor_data")
        profile = qos_from({"qos_profile": a.get("qos_profile")}, "sensor_data")
        infos = self.node.get_publishers_info_by_topic(a["topic_name"])
        if not infos:
            return profile
        reliable = sum(i.qos_profile.reliability == ReliabilityPolicy.RELIABLE for i in infos)
        latched = sum(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos)
        if reliable == len(infos):
            profile.reliability = ReliabilityPolicy.RELIABLE
        else:
            if reliable:
                call.out("Some, but not all, publishers are offering QoSReliabilityPolicy."
                         "RELIABLE. Falling back to QoSReliabilityPolicy.BEST_EFFORT as it "
                         "will connect to all publishers\n")  # fmt: skip
            profile.reliability = ReliabilityPolicy.BEST_EFFORT
        if latched == len(infos):
            profile.durability = DurabilityPolicy.TRANSIENT_LOCAL
        else:
            if latched:
                call.out("Some, but not all, publishers are offering QoSDurabilityPolicy."
                         "TRANSIENT_LOCAL. Falling back to QoSDurabilityPolicy.VOLATILE as it "
                         "will connect to all publishers\n")  # fmt: skip
            profile.durability = DurabilityPolicy.VOLATILE
        return profile

    def _topic_class(self, call: Call, a: dict) -> Any:
        """The message class: the given type's, else the topic's on the graph (hidden too)."""
        name = a["topic_name"]
        if a.get("message_type"):
            cls = load_class(a["message_type"], "msg")
            if cls is None:
                raise RuntimeError("The passed message type is invalid")
            return cls
        types = dict(self.graph.topics(True)).get(name)
        if not types:
            call.out(f"WARNING: topic [{name}] does not appear to be published yet\n")
            raise RuntimeError("Could not determine the type for the passed topic")
        if len(types) > 1:
            raise RuntimeError(
                f"Cannot echo topic '{name}', as it contains more than one type: "
                f"[{', '.join(types)}]"
            )
        cls = load_class(types[0], "msg")
        if cls is None:  # on the graph, but not importable here: what rosidl raises
            raise RuntimeError(f"The message type '{types[0]}' is invalid")
        return cls

    @runs("topic echo")
    def _topic_echo(self, call: Call, a: dict):
        used = [k for k in UNSUPPORTED_ECHO if a.get(k)]
        if used:
            return f"the emulated ros2 does not print topic echo --{used[0].replace('_', '-')}"
        field = None
        if a.get("field") is not None:
            field = [p for p in a["field"].split(".") if p]
            if not field:
                return f"Invalid field value '{a['field']}'"
        qos = self._echo_qos(call, a)
        cls = self._topic_class(call, a)
        got: queue.Queue = queue.Queue(maxsize=1000)
        sub = self.node.create_subscription(
            cls, a["topic_name"], lambda m: got.full() or got.put(m), qos
        )
        truncate = None if a.get("full_length") else a.get("truncate_length", 128)
        deadline = time.monotonic() + a["timeout"] if a.get("timeout") else math.inf
        try:
            while time.monotonic() < deadline:
                call.wait(0)  # Interrupted on SIGINT
                try:
                    msg = got.get(timeout=min(0.05, max(deadline - time.monotonic(), 0)))
                except queue.Empty:
                    continue
                for part in field or ():
                    try:
                        msg = getattr(msg, part)
                    except AttributeError as exc:
                        raise RuntimeError(f"Invalid field '{'.'.join(field)}': {exc}") from None
                if hasattr(msg, "get_fields_and_field_types"):
                    values = plain(msg, byte_chars=True)
                    call.out(echo_yaml(values, a.get("no_arr"), truncate, a.get("no_str")))
                else:  # a field's plain value is printed as print() does it
                    call.out(f"{msg}\n---\n")
                if a.get("once"):
                    return 0
        finally:
            self.node.destroy_subscription(sub)
        return 0

    @runs("topic hz")
    def _topic_hz(self, call: Call, a: dict):
        if a.get("filter_expr"):
            return "the emulated ros2 does not run topic hz --filter"
        name = a["topic_name"]
        warned = False
        while not (types := dict(self.graph.topics(True)).get(name)):
            if not warned:  # get_msg_class(blocking=True)
                call.out(f"WARNING: topic [{name}] does not appear to be published yet\n")
                warned = True
            call.wait(0.1)
        cls = load_class(types[0], "msg")
        if cls is None:
            raise RuntimeError(f"The message type '{types[0]}' is invalid")
        times: list[float] = []
        sub = self.node.create_subscription(
            cls, name, lambda _m: times.append(time.monotonic()), qos_profile_sensor_data, raw=True
        )
        printed = 0
        try:
            while True:
                call.wait(1.0)
                window = times[-a["window_size"] :]
                if len(window) < 2 or len(times) == printed:
                    continue
                printed = len(times)
                deltas = [b - x for x, b in zip(window, window[1:])]
                mean = sum(deltas) / len(deltas)
                std = math.sqrt(sum((d - mean) ** 2 for d in deltas) / len(deltas))
                call.out(
                    f"average rate: {1.0 / mean:.3f}\n\tmin: {min(deltas):.3f}s max: "
                    f"{max(deltas):.3f}s std dev: {std:.5f}s window: {len(window)}\n"
                )
        finally:
            self.node.destroy_subscription(sub)

    @runs("topic bw")
    def _topic_bw(self, call: Call, a: dict):
        from astiop.ros2.verbs.topic_bw import report_text

        name = a["topic_name"]
        while not (types := dict(self.graph.topics(True)).get(name)):
            call.wait(0.1)  # get_msg_class(blocking=True), silently (bw.py)
        cls = load_class(types[0], "msg")
        got: list[tuple[float, int]] = []
        sub = self.node.create_subscription(
            cls, name, lambda data: got.append((time.monotonic(), len(data))),
            qos_profile_sensor_data, raw=True,
        )  # fmt: skip
        call.out(f"Subscribed to [{name}]\n")
        try:
            while True:  # bw.py's timer: a report each second once two messages came
                call.wait(1.0)
                seen, now = got[-a["window_size"] :], time.monotonic()
                if len(seen) >= 2:
                    rate = sum(size for _, size in seen) / (now - seen[0][0])
                    call.out(report_text(rate, [size for _, size in seen]) + "\n")
        finally:
            self.node.destroy_subscription(sub)

    @runs("topic pub")
    def _topic_pub(self, call: Call, a: dict):
        cls = load_class(a["message_type"], "msg")
        if cls is None:
            raise RuntimeError("The passed message type is invalid")
        text = a.get("stdin_values") if a.get("stdin") else a.get("values", "{}")
        values = yaml.safe_load(text)
        if not isinstance(values, dict):
            return "The passed value needs to be a dictionary in YAML format"
        times = 1 if a.get("once") else a.get("times", 0)
        wait_for = a.get("wait_matching_subscriptions")
        wait_for = int(times != 0) if wait_for is None else wait_for
        max_wait = a.get("max_wait_time_secs")
        if wait_for == 0 and max_wait is not None:
            return ("--max-wait-time-secs option is only effective with "
                    "--wait-matching-subscriptions, --once or --times")  # fmt: skip
        pub = self.node.create_publisher(cls, a["topic_name"], qos_from(a, "default"))
        try:
            return self._publish(call, a, pub, cls, values, times, wait_for, max_wait)
        finally:
            self.node.destroy_publisher(pub)

    def _publish(self, call, a, pub, cls, values, times, wait_for, max_wait):
        waited, ticks = 0.0, 0
        while pub.get_subscription_count() < wait_for:
            if not ticks:  # said once a second, checked every 100 ms
                call.out(f"Waiting for at least {wait_for} matching subscription(s)...\n")
            if max_wait is not None and max_wait <= waited:
                return (f"Timed out waiting for subscribers: Expected {wait_for} subcribers "
                        f"but only got {pub.get_subscription_count()} subscribers")  # fmt: skip
            ticks = (ticks + 1) % 10
            call.wait(0.1)
            waited += 0.1
        msg = cls()
        try:
            stamps = set_message_fields(msg, values, expand=self.distro != "humble")
        except Exception as exc:  # noqa: BLE001 - whatever rosidl raises, ros2cli says so
            return f"Failed to populate field: {exc}"
        call.out("publisher: beginning loop\n")
        period, count = 1.0 / a["rate"], 0
        next_at = time.monotonic()
        while True:
            now = self.node.get_clock().now().to_msg()
            for stamp in stamps:
                stamp(now)
            count += 1
            if a.get("print", 1) and count % a.get("print", 1) == 0:
                call.out(f"publishing #{count}: {msg!r}\n\n")
            pub.publish(msg)
            if times and count >= times:
                break
            next_at += period
            call.wait(max(next_at - time.monotonic(), 0.0))
        call.wait(a.get("keep_alive", 0.1))  # for the messages to reach the wire
        return 0
