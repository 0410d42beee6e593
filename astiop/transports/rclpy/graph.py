"""The robot's graph through rclpy's graph API, as `ros2 ... list` would list it, and the QoS
to read a topic with, matched to its publishers (as ros2topic's echo chooses it)."""

from __future__ import annotations

import threading
import time
from typing import Any

from rclpy.action.graph import get_action_server_names_and_types_by_node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from astiop.transports.live_catalog import GraphLists
from astiop.transports.rclpy.node import RosProcess

# rcl_interfaces/msg/ParameterType -> `ros2 param list --param-type` (ros2param/api/__init__.py)
PARAM_TYPES = {
    1: "boolean",
    2: "integer",
    3: "double",
    4: "string",
    5: "byte array",
    6: "boolean array",
    7: "integer array",
    8: "double array",
    9: "string array",
}


def hidden(name: str) -> bool:
    """rclpy's topic_or_service_is_hidden: a name part that starts with an underscore."""
    return any(part.startswith("_") for part in name.split("/"))


def full_name(namespace: str, name: str) -> str:
    return f"{namespace.rstrip('/')}/{name}"


_read: dict[int, tuple[float, GraphLists]] = {}  # id(proc) -> (when, lists): the last read
_read_lock = threading.Lock()


def node_sections(node: Any, target: str, include_hidden: bool = False) -> dict:
    """What `ros2 node info` lists of one node (ros2node/api), as (name, types) per section."""
    from rclpy.action import (
        get_action_client_names_and_types_by_node,
        get_action_server_names_and_types_by_node,
    )

    ns, _, leaf = target.rpartition("/")
    ns = ns or "/"
    sections = {
        "Subscribers": node.get_subscriber_names_and_types_by_node(leaf, ns),
        "Publishers": node.get_publisher_names_and_types_by_node(leaf, ns),
        "Service Servers": node.get_service_names_and_types_by_node(leaf, ns),
        "Service Clients": node.get_client_names_and_types_by_node(leaf, ns),
        "Action Servers": get_action_server_names_and_types_by_node(node, leaf, ns),
        "Action Clients": get_action_client_names_and_types_by_node(node, leaf, ns),
    }
    return {
        k: sorted((n, ", ".join(t)) for n, t in v if include_hidden or not hidden(n))
        for k, v in sections.items()
    }


def read_lists(proc: RosProcess, max_age_s: float = 0.0) -> GraphLists:
    """Topics, services, actions and nodes from this process's DDS discovery cache (no call);
    `max_age_s`: a read that recent is shared (a fleet's gateways poll one graph, each robot
    every second: read once for all of them, not once per robot)."""
    with _read_lock:
        last = _read.get(id(proc))
        if max_age_s > 0 and last is not None and time.monotonic() - last[0] <= max_age_s:
            return last[1]
        lists = _read_now(proc)
        _read[id(proc)] = (time.monotonic(), lists)
        return lists


def _read_now(proc: RosProcess) -> GraphLists:
    node = proc.node
    me = full_name(node.get_namespace(), node.get_name())
    others = [
        (n, ns) for n, ns in node.get_node_names_and_namespaces()
        if not n.startswith("_") and full_name(ns, n) != me
    ]  # fmt: skip
    # services and actions as their servers offer them: a client (this process's own, kept
    # for the next call, or another's) is not a service the robot has (rmw lists both)
    services, actions = set(), set()
    for n, ns in others:
        try:
            served = node.get_service_names_and_types_by_node(n, ns)
            offered = get_action_server_names_and_types_by_node(node, n, ns)
        except Exception:  # noqa: BLE001 - the node left between the two reads
            continue
        services |= {(name, t[0]) for name, t in served if t and not hidden(name)}
        actions |= {(name, t[0]) for name, t in offered if t}
    return {
        "topic": sorted(
            (n, t[0]) for n, t in node.get_topic_names_and_types() if t and not hidden(n)
        ),
        "service": sorted(services),
        "action": sorted(actions),
        "node": sorted((full_name(ns, n), "") for n, ns in others),
    }


def read_params(proc: RosProcess, nodes: list[str], timeout: float) -> list[tuple[str, str]]:
    """("/node name", type) of each node's parameters, through its parameter services."""
    from rcl_interfaces.srv import GetParameterTypes, ListParameters

    listed: list[tuple[str, str]] = []
    for node_name in nodes:
        try:
            names = proc.call(
                ListParameters, f"{node_name}/list_parameters", ListParameters.Request(),
                timeout,
            ).result.names  # fmt: skip
            types = proc.call(
                GetParameterTypes,
                f"{node_name}/get_parameter_types",
                GetParameterTypes.Request(names=list(names)),
                timeout,
            ).types
        except Exception:  # noqa: BLE001 - a node without parameter services lists none
            continue
        listed += [(f"{node_name} {n}", PARAM_TYPES.get(t, "")) for n, t in zip(names, types)]
    return sorted(listed)


def latched(proc: RosProcess, topic: str) -> bool:
    """Every publisher of `topic` keeps its last message for a new subscriber (transient local):
    `ros2 topic echo --once` prints that message at once."""
    infos = proc.node.get_publishers_info_by_topic(topic)
    return bool(infos) and all(
        i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos
    )


def matched_qos(proc: RosProcess, topic: str, depth: int = 10) -> QoSProfile:
    """Best effort if any publisher is, transient local if every publisher is."""
    infos = proc.node.get_publishers_info_by_topic(topic)
    best_effort = any(i.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT for i in infos)
    latched = bool(infos) and all(
        i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos
    )
    return QoSProfile(
        depth=depth,
        reliability=ReliabilityPolicy.BEST_EFFORT if best_effort else ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )
