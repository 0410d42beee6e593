"""What the robot reported, as one immutable snapshot every layer above the robot reads.

Both backends build it from the same ROS 2 messages (`from_messages`), so the console shows
the simulator and the real robot alike. A topic the robot lacks leaves its field `None`:
absent, never zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from astiop.ros2.profile import AMCL_POSE, TF
from astiop.ros2.roles import ROLES, TF_ROLES
from astiop.ros2.transforms import ODOM, base_pose, map_pose, tree, yaw_of
from astiop.sim.kinematics import ASTIBOT, inverse_kinematics

MAX_WHEEL_SPEED = ASTIBOT.max_wheel_speed  # rad/s at the wheel, the motor limit


def wheel_speeds(vx: float, vy: float, wz: float) -> tuple[float, float, float, float]:
    """FL, FR, RL, RR from the body velocity (the ASTIbot's inverse kinematics)."""
    fl, fr, rl, rr = (float(w) for w in inverse_kinematics(vx, vy, wz))
    return fl, fr, rl, rr


@dataclass(frozen=True)
class Pose2D:
    x: float
    y: float
    theta: float  # rad


@dataclass(frozen=True)
class Battery:
    percentage: float  # 0..1, as sensor_msgs/BatteryState
    voltage: float
    current: float
    charging: bool


@dataclass(frozen=True)
class Status:
    state: str  # idle, navigating, docking, charging, blocked, e_stopped, fault
    mode: str
    active_goal: str
    fault: str
    speed: float
    e_stopped: bool
    docked: bool


@dataclass(frozen=True)
class Scan:
    angle_min: float
    angle_increment: float
    ranges: np.ndarray  # m; inf where nothing was hit
    stamp: float


@dataclass(frozen=True)
class Obstacle:
    kind: str
    distance: float
    bearing: float
    x: float
    y: float
    size: float


@dataclass(frozen=True)
class Conveyor:
    running: bool
    direction: int
    loaded: bool
    lamp: str


@dataclass(frozen=True)
class RobotEvent:
    seq: int
    t: float  # robot clock
    kind: str
    severity: str  # info | warning | error
    message: str


@dataclass(frozen=True)
class TopicStat:
    name: str
    type: str
    nominal_hz: float  # 0: unknown or on change
    measured_hz: float
    age_s: float  # since the last message (inf: none yet)
    count: int


@dataclass(frozen=True)
class OccupancyGrid:
    """nav_msgs/OccupancyGrid: row-major cells from the origin, -1 unknown, 0..100 occupied."""

    resolution: float
    origin_x: float
    origin_y: float
    width: int
    height: int
    cells: np.ndarray = field(repr=False)  # shape (height, width), int8

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        return (
            self.origin_x,
            self.origin_y,
            self.origin_x + self.width * self.resolution,
            self.origin_y + self.height * self.resolution,
        )


def grid_from_message(msg: dict[str, Any]) -> OccupancyGrid:
    """nav_msgs/OccupancyGrid as read; KeyError, TypeError or ValueError when malformed."""
    info = msg["info"]
    w, h = int(info["width"]), int(info["height"])
    cells = np.asarray(msg["data"], dtype=np.int8).reshape(h, w)
    origin = info["origin"]["position"]
    return OccupancyGrid(
        float(info["resolution"]), float(origin["x"]), float(origin["y"]), w, h, cells
    )


LOST = "lost"  # the robot is not heard: its state word, and how a goal it was on ended


@dataclass(frozen=True)
class RobotState:
    t: float  # the robot's clock: sim time, or receive time on a real robot
    pose: Pose2D | None = None
    velocity: tuple[float, float, float] | None = None  # vx, vy (m/s), wz (rad/s), robot frame
    wheel_speeds: tuple[float, float, float, float] | None = None  # FL, FR, RL, RR (rad/s)
    battery: Battery | None = None
    status: Status | None = None
    scan: Scan | None = None
    obstacles: tuple[Obstacle, ...] | None = None
    plan: tuple[tuple[float, float], ...] = ()
    conveyor: Conveyor | None = None
    e_stopped: bool = False
    event_seq: int = 0
    lost_s: float | None = None  # how long the robot has not been heard, once it is lost

    @property
    def speed(self) -> float | None:
        if self.velocity is None:
            return self.status.speed if self.status else None
        return math.hypot(self.velocity[0], self.velocity[1])

    @property
    def state_word(self) -> str:
        if self.lost_s is not None:
            return LOST  # nothing it last said holds any more, an E-STOP's effect included
        if self.e_stopped:
            return "e_stopped"
        return self.status.state if self.status else "unknown"

    @property
    def distance_remaining(self) -> float | None:
        """Along the plan from the robot, while there is one: to the end of the nearest
        segment, then the segments after it."""
        if not self.plan or self.pose is None:
            return None
        pts = np.asarray(self.plan, dtype=float)
        here = np.array([self.pose.x, self.pose.y])
        if len(pts) == 1:
            return float(np.hypot(*(pts[0] - here)))
        a, b = pts[:-1], pts[1:]
        ab = b - a
        t = np.clip(((here - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-12), 0.0, 1.0)
        gap = np.hypot(*(a + ab * t[:, None] - here).T)
        k = int(np.argmin(gap))
        lengths = np.hypot(*ab.T)
        return float(np.hypot(*(b[k] - here)) + lengths[k + 1 :].sum())

    def with_e_stop(self, engaged: bool) -> RobotState:
        return replace(self, e_stopped=engaged or self.e_stopped)

    def with_lost(self, lost_s: float | None) -> RobotState:
        return self if lost_s is None else replace(self, lost_s=lost_s)


def _f(value: Any, default: float = math.nan) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return default
    return v


# the state's roles, by the ASTIbot's names (its pose is its /robot_pose, not the transforms)
ASTIBOT_NAMES = {r.name: "" if r.name in TF_ROLES else r.key for r in ROLES if r.state}


def role_names(profile: Any) -> dict[str, str]:
    """Role -> the robot's topic for the state's roles (the ASTIbot's without a profile)."""
    if profile is None:
        return dict(ASTIBOT_NAMES)
    return {r: profile.name(r) or "" for r in ASTIBOT_NAMES}


GOAL_STATUS = "action_msgs/msg/GoalStatusArray"
ACTIVE_GOAL = (1, 2, 3)  # action_msgs/msg/GoalStatus: ACCEPTED, EXECUTING, CANCELING


def goal_status_topic(profile: Any) -> str | None:
    """A robot that reports no status of its own but navigates by an action (Nav2): its action
    server's goal status topic tells whether a goal runs (rcl_action: <action>/_action/status)."""
    if profile is None or profile.has("status") or profile.kind("navigation") != "action":
        return None
    return f"{profile.name('navigation')}/_action/status"


def _from_goal_status(msg: dict[str, Any], velocity: tuple | None, action: str) -> Status:
    running = any(int(_f(g.get("status"), 0)) in ACTIVE_GOAL for g in msg.get("status_list") or [])
    speed = math.hypot(velocity[0], velocity[1]) if velocity else 0.0
    goal = f"a {action} goal" if running else ""  # a goal runs, whoever sent it
    return Status("navigating" if running else "idle", "", goal, "", speed, False, False)


def _pose(msg: dict[str, Any]) -> Pose2D:
    """A Pose2D, or the pose of a PoseWithCovarianceStamped or an Odometry."""
    if "x" in msg:
        return Pose2D(_f(msg.get("x")), _f(msg.get("y")), _f(msg.get("theta")))
    p = msg.get("pose", {}).get("pose", {})
    pos = p.get("position", {})
    return Pose2D(_f(pos.get("x")), _f(pos.get("y")), yaw_of(p.get("orientation", {})))


def _tf_pose(messages: dict[str, dict[str, Any]], n: dict[str, str], pose_type: str):
    """map → odom ∘ odom → base from TF: amcl's map → odom comes with every scan, its pose only
    after update_min_d of motion (nav2_amcl), so the chain is fresh where /amcl_pose lags; the
    last /amcl_pose where TF has no map frame (yet); odometry's pose for a /tf pose without one."""
    tf = [messages.get(n["static_transforms"]), messages.get(n["transforms"])]
    odom = messages.get(n["odometry"])
    found = map_pose(tf, odom)
    if found is not None:
        return Pose2D(*found[0])
    if pose_type == AMCL_POSE:
        p = messages.get(n["pose"])
        return _pose(p) if p is not None else None
    found = base_pose(tree(*tf), ODOM)
    if found is not None:
        return Pose2D(*found[0])
    return _pose(odom) if odom is not None else None


def battery_fraction(value: Any, units: str | None) -> float:
    """BatteryState.percentage as 0-1: "percent" robots (a TurtleBot3) send 0-100; a robot that
    did not say sends the message's 0-1, and a reading over 1 can only be a percentage."""
    v = _f(value)
    if units == "percent" or (units is None and v > 1.0):
        return v / 100.0
    return v


def _ranges(sc: dict[str, Any]) -> np.ndarray:
    """The beams in m, inf where nothing was hit: sensor_msgs/LaserScan says a range outside
    [range_min, range_max] is to be discarded (a lidar's no-return 0.0 is not an obstacle)."""
    ranges = np.array([_f(r, math.inf) for r in sc.get("ranges") or []], dtype=float)
    lo, hi = _f(sc.get("range_min"), 0.0), _f(sc.get("range_max"), math.inf)
    bad = ~np.isfinite(ranges) | (ranges <= 0.0) | (ranges < lo) | (ranges > hi)
    ranges[bad] = math.inf
    return ranges


def from_messages(
    t: float,
    messages: dict[str, dict[str, Any]],
    *,
    e_stopped: bool = False,
    event_seq: int = 0,
    profile: Any = None,
) -> RobotState:
    """The state from the latest message of each role's topic (missing roles stay `None`), the
    names from the robot's profile (ros2/profile.py; the ASTIbot's without one)."""
    n = role_names(profile)
    pose = velocity = wheels = battery = status = scan = obstacles = conveyor = None
    pose_match = profile.matches.get("pose") if profile is not None else None
    pose_type = pose_match.type if pose_match is not None else ""
    if pose_type in (AMCL_POSE, TF):
        pose = _tf_pose(messages, n, pose_type)
    elif (p := messages.get(n["pose"])) is not None:
        pose = _pose(p)
    if (o := messages.get(n["odometry"])) is not None:
        tw = o.get("twist", {}).get("twist", {})
        lin, ang = tw.get("linear", {}), tw.get("angular", {})
        velocity = (_f(lin.get("x"), 0.0), _f(lin.get("y"), 0.0), _f(ang.get("z"), 0.0))
        if pose is None and profile is None:  # no profile to say what the pose is: odometry's
            pose = _pose(o)
    if velocity is not None and all(math.isfinite(v) for v in velocity):
        wheels = wheel_speeds(*velocity)
    if (b := messages.get(n["battery"])) is not None:
        units = profile.units.battery_percentage if profile is not None else None
        battery = Battery(
            battery_fraction(b.get("percentage"), units),
            _f(b.get("voltage")),
            _f(b.get("current")),
            int(_f(b.get("power_supply_status"), 0)) == 1,  # POWER_SUPPLY_STATUS_CHARGING
        )
    if (s := messages.get(n["status"])) is not None:
        status = Status(
            str(s.get("state", "")),
            str(s.get("mode", "")),
            str(s.get("active_goal", "")),
            str(s.get("fault", "")),
            _f(s.get("speed"), 0.0),
            bool(s.get("e_stopped", False)),
            bool(s.get("docked", False)),
        )
    if status is None and (goals := messages.get(goal_status_topic(profile) or "")) is not None:
        status = _from_goal_status(goals, velocity, profile.name("navigation"))
    if (sc := messages.get(n["scan"])) is not None:
        stamp = sc.get("header", {}).get("stamp", {})
        scan = Scan(
            _f(sc.get("angle_min"), -math.pi),
            _f(sc.get("angle_increment"), 0.0),
            _ranges(sc),
            _f(stamp.get("sec"), 0.0) + _f(stamp.get("nanosec"), 0.0) * 1e-9,
        )
    if (ob := messages.get(n["obstacles"])) is not None:
        obstacles = tuple(
            Obstacle(
                str(o.get("kind", "unknown")),
                _f(o.get("distance")),
                _f(o.get("bearing")),
                _f(o.get("position", {}).get("x")),
                _f(o.get("position", {}).get("y")),
                _f(o.get("size"), 0.0),
            )
            for o in ob.get("obstacles") or []
        )
    plan: tuple[tuple[float, float], ...] = ()
    if (pl := messages.get(n["plan"])) is not None:
        points = [ps.get("pose", {}).get("position", {}) for ps in pl.get("poses") or []]
        plan = tuple((_f(p.get("x")), _f(p.get("y"))) for p in points)
    if (c := messages.get(n["conveyor"])) is not None:
        conveyor = Conveyor(
            bool(c.get("running")),
            int(_f(c.get("direction"), 0)),
            bool(c.get("loaded")),
            str(c.get("lamp", "")),
        )
    return RobotState(
        t=t,
        pose=pose,
        velocity=velocity,
        wheel_speeds=wheels,
        battery=battery,
        status=status,
        scan=scan,
        obstacles=obstacles,
        plan=plan,
        conveyor=conveyor,
        e_stopped=e_stopped or bool(status and status.e_stopped),
        event_seq=event_seq,
    )


def live_topic_stats(topics: dict, sources: dict, now: float) -> list[TopicStat]:
    """Each catalog topic's statistics from what watches it on a live robot (anything with
    rate(now), age(now) and count); a topic nothing watches is absent (NaN), never zero."""
    stats = []
    for name, spec in sorted(topics.items()):
        s = sources.get(name)
        if s is None:
            stats.append(TopicStat(name, spec.type, spec.rate_hz, math.nan, math.nan, 0))
        else:
            stats.append(TopicStat(name, spec.type, spec.rate_hz, s.rate(now), s.age(now), s.count))
    return stats
