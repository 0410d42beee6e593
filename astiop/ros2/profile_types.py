"""What a robot's profile is: which of its names plays each role (`Match`), its units, its
limits and its map (`Profile`), and what the operator fixed of them (`ProfileSpec`). Matched
on the graph by profile.py, read from and written to profile files by profile_file.py."""

from __future__ import annotations

from dataclasses import dataclass, field

from astiop.ros2.roles import AMCL_POSE, ROLE_BY_NAME, ROLE_NAMES, TF, TF_ROLES


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
    battery_low: float | None = None  # %, below which the built-in alert says the battery is low

    def over(self, base: Limits) -> Limits:
        return Limits(
            *(
                mine if mine is not None else theirs
                for mine, theirs in (
                    (self.max_linear_speed, base.max_linear_speed),
                    (self.max_angular_speed, base.max_angular_speed),
                    (self.radius, base.radius),
                    (self.battery_low, base.battery_low),
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
        return [r for r in ROLE_NAMES if not self.has(r) and not ROLE_BY_NAME[r].optional]

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
                    ("battery_low", self.limits.battery_low),
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
