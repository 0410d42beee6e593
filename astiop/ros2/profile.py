"""The robot's profile: which of its topics, services and actions play which role, matched on
its graph by type first, then by conventional names, so astiop speaks of roles ("battery",
"pose") and the profile supplies the names (`/battery_status` on the ASTIbot, `/battery_state`
on a TurtleBot3). A profile file (profile_file.py) fixes what matching cannot know; what a
profile is (its dataclasses) is in profile_types.py."""

from __future__ import annotations

from typing import Any, Protocol

from astiop.ros2.profile_file import shipped
from astiop.ros2.profile_types import (  # ProfileSpec also read from here by transports/
    Match,
    Profile,
    ProfileSpec,
)
from astiop.ros2.roles import (
    AMCL_POSE,
    NAVIGATE_TO_POSE,  # noqa: F401 - read from here by transports/live_catalog.py
    ROLE_BY_NAME,
    ROLES,
    TF,
    Role,
)


class Graph(Protocol):
    """What matching reads of a robot's catalog (ros2/catalog.py's Catalog, which imports this
    module to match the ASTIbot's own profile)."""

    topics: dict[str, Any]
    services: dict[str, Any]
    actions: dict[str, Any]
    nodes: tuple[str, ...]


def _entries(catalog: Graph, kind: str) -> dict[str, str]:
    table = {"topic": catalog.topics, "service": catalog.services, "action": catalog.actions}
    return {name: spec.type for name, spec in table[kind].items()}


def _local(name: str, namespace: str) -> str | None:
    """The name inside the robot's namespace, or None when it lies outside it."""
    if not namespace:
        return name
    if name.startswith(namespace + "/"):
        return name[len(namespace) :]
    return None


def _match(role: Role, catalog: Graph, namespace: str, entries: dict) -> Match:
    for kind, typ in role.kinds:
        found = []
        for name, t in entries[kind].items():
            local = _local(name, namespace)
            if t != typ or local is None:
                continue
            if any(w in local for w in role.never):
                continue
            if role.by_name_only and local not in role.names:
                continue
            found.append((local, name))
        if not found:
            continue
        named = [(role.names.index(loc), name) for loc, name in found if loc in role.names]
        if named:
            name = min(named)[1]
            why = "by type" if len(found) == 1 else f"by name, among {len(found)} of its type"
        elif len(found) == 1:
            name, why = found[0][1], "by type"
        else:
            name = sorted(n for _, n in found)[0]
            why = f"the first of {len(found)} of its type: fix it in a profile file"
        if role.by_name_only:
            why = "by name"
        if kind == "topic" and role.kinds.index((kind, typ)) > 0:
            why += f", for want of a {role.kinds[0][1].rsplit('/', 1)[-1]}"
        return Match(role.name, kind, name, typ, why)
    looked = ", ".join(t.rsplit("/", 1)[-1] for _, t in role.kinds)
    return Match(role.name, "", "", "", f"no {looked} on the robot's graph")


def _fixed(
    role: str,
    name: str,
    catalog: Graph,
    entries: dict,
    source: str,
) -> Match:
    """A name the profile file gives: its kind and type as the graph has it, else as the role's
    first kind (the robot may not have announced it yet)."""
    if not name:
        return Match(role, "", "", "", f"none, says {source}")
    for kind, table in entries.items():
        if name in table:
            return Match(role, kind, name, table[name], f"set by {source}")
    kind, typ = ROLE_BY_NAME[role].kinds[0]
    return Match(role, kind, name, typ, f"set by {source} (not on the graph yet)", False)


def recognise(catalog: Graph) -> str:
    """The robot's make from its graph: a node or a type only that make has."""
    nodes = {n.rsplit("/", 1)[-1] for n in catalog.nodes}
    types = {s.type for s in catalog.topics.values()}
    if "astiop_msgs/msg/RobotStatus" in types or "astibot_base" in nodes:
        return "astibot"
    if "turtlebot3_node" in nodes:
        return "turtlebot3_burger"  # a Waffle says so in its profile: the slower limits first
    return "unknown"


def match_profile(catalog: Graph, spec: ProfileSpec | None = None) -> Profile:
    """The profile of the robot on `catalog`: what `spec` fixes, over what astiop ships for the
    robot's make (recognised on the graph unless `spec` names it), over what matching finds."""
    spec = spec or ProfileSpec()
    make = spec.make or recognise(catalog)
    base = shipped(make)
    if base is not None:
        spec = ProfileSpec(
            make,
            spec.namespace,
            {**base.roles, **spec.roles},
            spec.units.over(base.units),
            spec.limits.over(base.limits),
            spec.source or base.source,
            spec.map.over(base.map),
        )
    entries = {k: _entries(catalog, k) for k in ("topic", "service", "action")}
    ns = spec.namespace
    source = spec.source or "the graph"
    matches = {}
    for role in ROLES:
        if role.name in spec.roles:
            name = spec.roles[role.name]
            full = ns + name if name and ns and not name.startswith(ns + "/") else name
            matches[role.name] = _fixed(role.name, full, catalog, entries, source)
        else:
            matches[role.name] = _match(role, catalog, ns, entries)
    matches["pose"] = _pose_source(matches)
    return Profile(make, ns, matches, spec.units, spec.limits, source, spec.map)


def _pose_source(matches: dict[str, Match]) -> Match:
    """The pose's match, its "why" saying how the state builds it from TF where it does."""
    pose, tf = matches["pose"], matches.get("transforms")
    on_tf = tf is not None and bool(tf.name)
    if pose.type == AMCL_POSE and tf is not None and on_tf:
        # amcl publishes its pose only after update_min_d/update_min_a of motion, but map → odom
        # on /tf with every scan: composed with odom → base, the pose is as fresh as odometry
        how = f"; between its updates, {tf.name}'s map → odom ∘ odom → base"
    elif pose.type == TF:
        how = ": map → base_footprint or base_link (odom → base while it has no map frame)"
    else:
        return pose
    return Match(pose.role, pose.kind, pose.name, pose.type, pose.why + how)
