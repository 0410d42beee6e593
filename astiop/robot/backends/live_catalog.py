"""The robot's live graph described with astiop's catalog where the names and types match (an
unknown service is treated as actuating). Both ROS 2 backends read the graph their own way
(`ros2 ... list`, or rclpy's graph API) into the same lists."""

from __future__ import annotations

from dataclasses import replace

from astiop.ros2.catalog import (  # noqa: F401 - RELEASE: its home for the transports
    RELEASE,
    ActionSpec,
    Catalog,
    ParamSpec,
    ServiceSpec,
    TopicSpec,
    astibot_catalog,
)
from astiop.ros2.render import STAMPED

# verb -> sorted (name, type) pairs; "node": (name, ""); "param": ("/node name", type)
GraphLists = dict[str, list[tuple[str, str]]]
VERBS = ("topic", "service", "action", "node", "param")  # what a graph read lists


def nothing_listed() -> GraphLists:
    """The lists of a graph not read (yet)."""
    return {verb: [] for verb in VERBS}


def stop_service_type(catalog: Catalog) -> str:
    """/stop's type as the graph has it, else as the robot's catalog names it (a process that
    did not read the graph: an E-STOP)."""
    spec = catalog.services.get("/stop") or astibot_catalog().services["/stop"]
    return spec.type


def _params(known: Catalog, listed: list[tuple[str, str]]) -> dict[tuple[str, str], ParamSpec]:
    """The robot's parameters: astiop's own entry where it has one (limits, writable), else
    read-only with the type the robot gave. Before the robot lists any, astiop's table."""
    if not listed:
        return dict(known.params)
    params = {}
    for key, typ in listed:
        node, name = key.split(" ", 1)
        spec = known.params.get((node, name))
        params[(node, name)] = (
            replace(spec, type=typ) if spec else ParamSpec(node, name, None, type=typ)
        )
    return params


def describe_graph(lists: GraphLists) -> Catalog:
    known = astibot_catalog()
    nodes = tuple(n for n, _ in lists["node"]) or known.nodes
    cat = Catalog(nodes=nodes, params=_params(known, lists.get("param", [])))
    for name, typ in lists["topic"]:
        spec = known.topics.get(name)
        if name == "/cmd_vel" and spec and typ == STAMPED:  # Jazzy's diff_drive_controller
            spec = replace(spec, type=typ)
        cat.topics[name] = spec if spec and spec.type == typ else TopicSpec(name, typ, 0, "?")
    for name, typ in lists["service"]:
        spec = known.services.get(name)
        # an unknown service is treated as actuating: it needs confirmation
        cat.services[name] = (
            spec if spec and spec.type == typ else ServiceSpec(name, typ, "?", True)
        )
    for name, typ in lists["action"]:
        spec = known.actions.get(name)
        cat.actions[name] = spec if spec and spec.type == typ else ActionSpec(name, typ, "?")
    return cat
