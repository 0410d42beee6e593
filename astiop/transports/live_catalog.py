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
from astiop.ros2.profile import NAVIGATE_TO_POSE, ProfileSpec, match_profile
from astiop.ros2.render import STAMPED

# Cancels every goal of an action server when sent with a zero goal id and stamp (the E-STOP
# on a robot without a stop service)
CANCEL_GOAL = "action_msgs/srv/CancelGoal"
NAVIGATE = "/navigate_to_pose"  # Nav2's, and the ASTIbot's: the default before the graph is read

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


def navigation_actions(catalog: Catalog, namespace: str) -> list[str]:
    """The robot's NavigateToPose action servers: an E-STOP on a robot without a stop service
    cancels every goal of each (another client's too)."""
    return [
        a.name
        for a in catalog.actions.values()
        if a.type == NAVIGATE_TO_POSE and (not namespace or a.name.startswith(namespace + "/"))
    ]


def _params(
    known: Catalog, listed: list[tuple[str, str]], namespace: str = ""
) -> dict[tuple[str, str], ParamSpec]:
    """The robot's parameters: astiop's own entry where it has one (limits, writable), else
    read-only with the type the robot gave. Before the robot lists any, astiop's table. A
    fleet's robot (`namespace`): astiop's entries under its namespace (/astibot_2/navigator)."""
    ns = namespace.rstrip("/")
    if not listed:
        return {(ns + n, p): replace(spec, node=ns + n) for (n, p), spec in known.params.items()}
    params = {}
    for key, typ in listed:
        node, name = key.split(" ", 1)
        own = node[len(ns) :] if ns and node.startswith(ns + "/") else node
        spec = known.params.get((own, name))
        params[(node, name)] = (
            replace(spec, node=node, type=typ) if spec else ParamSpec(node, name, None, type=typ)
        )
    return params


def describe_graph(lists: GraphLists, fixed: ProfileSpec | None = None) -> Catalog:
    """The catalog of the graph read, with the robot's profile matched on it, over what the
    operator `fixed` (a profile file, a namespace)."""
    known = astibot_catalog()
    nodes = tuple(n for n, _ in lists["node"]) or known.nodes
    namespace = fixed.namespace if fixed is not None else ""
    cat = Catalog(nodes=nodes, params=_params(known, lists.get("param", []), namespace or ""))
    for name, typ in lists["topic"]:
        spec = known.topics.get(name)
        if name == "/cmd_vel" and spec and typ == STAMPED:  # Jazzy's diff_drive_controller
            spec = replace(spec, type=typ)
        cat.topics[name] = spec if spec and spec.type == typ else TopicSpec(name, typ, 0, "?")
    for name, typ in lists["service"]:
        service = known.services.get(name)
        # an unknown service is treated as actuating: it needs confirmation
        cat.services[name] = (
            service if service and service.type == typ else ServiceSpec(name, typ, "?", True)
        )
    for name, typ in lists["action"]:
        action = known.actions.get(name)
        cat.actions[name] = action if action and action.type == typ else ActionSpec(name, typ, "?")
    cat.profile = match_profile(cat, fixed)
    return cat


class LiveGraph:
    """The robot's graph as this process last read it, shared by a live backend and its helpers:
    its lists, their catalog (both replaced at each read) and the robot's name for a role."""

    def __init__(self, catalog: Catalog, fixed: ProfileSpec, lists: GraphLists | None = None):
        self.catalog = catalog
        self.fixed = fixed  # what the operator fixed: a profile file, a namespace
        self.lists = lists if lists is not None else nothing_listed()
        self.discovered = True  # False: not read yet (an E-STOP from a new process)

    def name(self, role: str, default: str = "") -> str:
        """The robot's name for `role` (its profile); before the graph is read, `default` under
        the robot's namespace ("" for a role without a conventional name)."""
        name = self.catalog.profile.name(role) if self.catalog.profile else None
        return name or (self.fixed.namespace + default if default else "")
