"""The robot's profile: which of its topics, services and actions play which role, matched on
its graph by type first, then by conventional names, so astiop speaks of roles ("battery",
"pose") and the profile supplies the names (`/battery_status` on the ASTIbot, `/battery_state`
on a TurtleBot3). A profile file (profile_file.py) fixes what matching cannot know."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from astiop.ros2.roles import (
    AMCL_POSE,
    NAVIGATE_TO_POSE,  # noqa: F401 - read from here by transports/live_catalog.py
    ROLE_BY_NAME,
    ROLE_NAMES,
    ROLES,
    TF,
    TF_ROLES,
    Role,
)

if TYPE_CHECKING:
    from astiop.ros2.catalog import Catalog


@dataclass(frozen=True)
class Match:
    role: str
    kind: str  # topic | service | action; "" when nothing plays the role
    name: str  # the full name on the robot's graph, namespace included
    type: str
    why: str  # "type …", "name …", "the profile file", or why nothing matched
    announced: bool = True  # False: a profile file names it and the graph has not shown it yet


@dataclass(frozen=True)
class Units:
    # "fraction" as sensor_msgs/BatteryState defines it (0-1), or "percent" (0-100, as a
    # TurtleBot3 fills it); None: not said (read as a fraction, a reading over 1 as percent)
    battery_percentage: str | None = None

    def over(self, base: Units) -> Units:
        return Units(self.battery_percentage or base.battery_percentage)


@dataclass(frozen=True)
class Limits:
    max_linear_speed: float | None = None  # m/s
    max_angular_speed: float | None = None  # rad/s
    radius: float | None = None  # m, the body's footprint

    def over(self, base: Limits) -> Limits:
        return Limits(
            *(
                mine if mine is not None else theirs
                for mine, theirs in (
                    (self.max_linear_speed, base.max_linear_speed),
                    (self.max_angular_speed, base.max_angular_speed),
                    (self.radius, base.radius),
                )
            )
        )


@dataclass(frozen=True)
class MapSpec:
    """The map the robot navigates on: its named locations belong to it (a place saved on one
    robot's map means nothing on another's), and goals must fall inside its geofence."""

    name: str = ""  # "" = the robot's make: robots of one make share their places
    geofence: tuple[float, float, float, float] | None = None  # x_min, y_min, x_max, y_max (m)

    def over(self, base: MapSpec) -> MapSpec:
        return MapSpec(self.name or base.name, self.geofence or base.geofence)


@dataclass(frozen=True)
class ProfileSpec:
    """What the operator fixed (a profile file, --namespace): names by role ("" = the robot
    has none), units, limits; everything else is matched on the graph."""

    make: str = ""  # "" until known: then read from the graph (see `recognise`)
    namespace: str = ""
    roles: dict[str, str] = field(default_factory=dict)
    units: Units = Units()
    limits: Limits = Limits()
    source: str = ""  # where it was read: a file's path, "shipped astibot", ""
    map: MapSpec = MapSpec()


@dataclass(frozen=True)
class Profile:
    make: str  # astibot, turtlebot3_burger, ..., or "unknown"
    namespace: str
    matches: dict[str, Match]
    units: Units
    limits: Limits
    source: str  # "the graph", or the profile file and the graph
    map: MapSpec = MapSpec()

    @property
    def map_name(self) -> str:
        """Which map the robot's named locations belong to."""
        return self.map.name or self.make

    def name(self, role: str) -> str | None:
        """The robot's name for `role`, or None when nothing on the robot plays it."""
        m = self.matches.get(role)
        return m.name if m is not None and m.name else None

    def has(self, role: str) -> bool:
        return self.name(role) is not None

    def kind(self, role: str) -> str:
        m = self.matches.get(role)
        return m.kind if m is not None else ""

    def missing(self) -> list[str]:
        return [r for r in ROLE_NAMES if not self.has(r)]

    def pending(self) -> list[str]:
        """Roles a profile file names that the graph has not shown yet."""
        return [r for r, m in self.matches.items() if not m.announced]

    def state_topics(self) -> list[str]:
        """The topics the live state is built from, where the robot has them (TF only for a
        pose that is built from it: a 50 Hz /tf is not read for nothing)."""
        tf = self.matches.get("pose", Match("pose", "", "", "", "")).type in (AMCL_POSE, TF)
        return sorted(
            {
                m.name
                for m in self.matches.values()
                if m.kind == "topic"
                and ROLE_BY_NAME[m.role].state
                and (tf or m.role not in TF_ROLES)
            }
        )

    def as_dict(self) -> dict:
        return {
            "make": self.make,
            "namespace": self.namespace,
            "source": self.source,
            "roles": {
                r: {"kind": m.kind, "name": m.name, "type": m.type, "why": m.why}
                for r, m in self.matches.items()
            },
            "missing": self.missing(),
            "units": {"battery_percentage": self.units.battery_percentage or "fraction"},
            "limits": {
                k: v
                for k, v in (
                    ("max_linear_speed", self.limits.max_linear_speed),
                    ("max_angular_speed", self.limits.max_angular_speed),
                    ("radius", self.limits.radius),
                )
                if v is not None
            },
            "map": {"name": self.map_name, "geofence": list(self.map.geofence or []) or None},
        }


def normalise_namespace(ns: str) -> str:
    """ "/tb3_1", "tb3_1/" -> "/tb3_1"; "" or "/" -> ""; ValueError when not a ROS name."""
    ns = ns.strip().strip("/")
    if not ns:
        return ""
    for part in ns.split("/"):
        if not part or not (part[0].isalpha() or part[0] == "_"):
            raise ValueError(f"not a ROS 2 namespace: /{ns}")
        if not all(c.isalnum() or c == "_" for c in part):
            raise ValueError(f"not a ROS 2 namespace: /{ns}")
    return "/" + ns


def _entries(catalog: Catalog, kind: str) -> dict[str, str]:
    table = {"topic": catalog.topics, "service": catalog.services, "action": catalog.actions}
    return {name: spec.type for name, spec in table[kind].items()}


def _local(name: str, namespace: str) -> str | None:
    """The name inside the robot's namespace, or None when it lies outside it."""
    if not namespace:
        return name
    if name.startswith(namespace + "/"):
        return name[len(namespace) :]
    return None


def _match(role: Role, catalog: Catalog, namespace: str, entries: dict) -> Match:
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


def _fixed(role: str, name: str, catalog: Catalog, entries: dict, source: str) -> Match:
    """A name the profile file gives: its kind and type as the graph has it, else as the role's
    first kind (the robot may not have announced it yet)."""
    if not name:
        return Match(role, "", "", "", f"none, says {source}")
    for kind, table in entries.items():
        if name in table:
            return Match(role, kind, name, table[name], f"set by {source}")
    kind, typ = ROLE_BY_NAME[role].kinds[0]
    return Match(role, kind, name, typ, f"set by {source} (not on the graph yet)", False)


def recognise(catalog: Catalog) -> str:
    """The robot's make from its graph: a node or a type only that make has."""
    nodes = {n.rsplit("/", 1)[-1] for n in catalog.nodes}
    types = {s.type for s in catalog.topics.values()}
    if "astiop_msgs/msg/RobotStatus" in types or "astibot_base" in nodes:
        return "astibot"
    if "turtlebot3_node" in nodes:
        return "turtlebot3_burger"  # a Waffle says so in its profile: the slower limits first
    return "unknown"


def match_profile(catalog: Catalog, spec: ProfileSpec | None = None) -> Profile:
    """The profile of the robot on `catalog`: what `spec` fixes, over what astiop ships for the
    robot's make (recognised on the graph unless `spec` names it), over what matching finds."""
    from astiop.ros2.profile_file import shipped

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
    if pose.type == AMCL_POSE and on_tf:
        # amcl publishes its pose only after update_min_d/update_min_a of motion, but map → odom
        # on /tf with every scan: composed with odom → base, the pose is as fresh as odometry
        how = f"; between its updates, {tf.name}'s map → odom ∘ odom → base"
    elif pose.type == TF:
        how = ": map → base_footprint or base_link (odom → base while it has no map frame)"
    else:
        return pose
    return Match(pose.role, pose.kind, pose.name, pose.type, pose.why + how)
