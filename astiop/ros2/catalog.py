"""The ASTIbot's ROS 2 graph: topics, services, actions, nodes and parameters.

A contract: prompts, the rules baseline, the benchmark and the tests all use these names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from astiop.ros2.profile_types import Profile

# The robot's release of its own latched stop: the operator's to call, never the model's
RELEASE = "/release"


@dataclass(frozen=True)
class TopicSpec:
    name: str
    type: str
    rate_hz: float  # 0: on change only
    publisher: str  # node, '' when the robot only listens
    subscriber: str = ""
    description: str = ""
    # "state": the live state is built from it, and it is recorded; "record": recorded only
    role: str = ""
    # the publisher's QoS, as a real driver sets it: "" reliable and volatile (depth 10),
    # "sensor_data" (best effort, depth 5), "transient_local" (latched: the last one kept)
    qos: str = ""

    @property
    def actuating(self) -> bool:
        return bool(self.subscriber) and not self.publisher


@dataclass(frozen=True)
class ServiceSpec:
    name: str
    type: str
    node: str
    actuating: bool
    description: str = ""
    needs_confirmation: bool = True
    starts_job: bool = False  # its success means the robot took a job on, not that it is done


@dataclass(frozen=True)
class ActionSpec:
    name: str
    type: str
    node: str
    description: str = ""


@dataclass(frozen=True)
class ParamSpec:
    node: str
    name: str
    value: float | int | str | bool | None  # None: listed by the robot, value not read
    writable: bool = False  # astiop writes only parameters whose limits it knows
    minimum: float | None = None
    maximum: float | None = None
    description: str = ""
    type: str = ""  # as `ros2 param list --param-type` prints it: double, integer, ...


@dataclass
class Catalog:
    topics: dict[str, TopicSpec] = field(default_factory=dict)
    services: dict[str, ServiceSpec] = field(default_factory=dict)
    actions: dict[str, ActionSpec] = field(default_factory=dict)
    nodes: tuple[str, ...] = ()
    params: dict[tuple[str, str], ParamSpec] = field(default_factory=dict)
    profile: Profile | None = None  # which names play which role (ros2/profile.py)

    def node_info(self, node: str) -> dict[str, list[tuple[str, str]]]:
        return {
            "Subscribers": [(t.name, t.type) for t in self.topics.values() if t.subscriber == node],
            "Publishers": [(t.name, t.type) for t in self.topics.values() if t.publisher == node],
            "Service Servers": [(s.name, s.type) for s in self.services.values() if s.node == node],
            "Action Servers": [(a.name, a.type) for a in self.actions.values() if a.node == node],
        }

    def state_topics(self) -> list[str]:
        """The topics the robot's live state is built from, where the robot has them."""
        if self.profile is not None:
            return [n for n in self.profile.state_topics() if n in self.topics]
        return [t.name for t in self.topics.values() if t.role == "state"]

    def recorded_topics(self) -> list[str]:
        """The topics a session recording keeps, where the robot has them."""
        kept = [t.name for t in self.topics.values() if t.role in ("state", "record")]
        return sorted(set(kept) | set(self.state_topics()))


_TOPICS = [
    TopicSpec(
        "/cmd_vel",
        "geometry_msgs/msg/Twist",
        0,
        "",
        "/astibot_base",
        "velocity command in the robot frame; clamped by safety",
    ),
    TopicSpec(
        "/odom",
        "nav_msgs/msg/Odometry",
        50,
        "/astibot_base",
        "",
        "wheel odometry: pose and velocity",
        role="state",
    ),
    TopicSpec(
        "/robot_pose",
        "geometry_msgs/msg/Pose2D",
        10,
        "/navigator",
        "",
        "pose in the map frame: x, y in m, theta in rad",
        role="state",
    ),
    TopicSpec(
        "/battery_status",
        "sensor_msgs/msg/BatteryState",
        1,
        "/battery_monitor",
        "",
        "voltage, current, charge; percentage is 0-1",
        role="state",
    ),
    TopicSpec(
        "/robot_status",
        "astiop_msgs/msg/RobotStatus",
        2,
        "/astibot_base",
        "",
        "state (idle, navigating, docking, charging, blocked, e_stopped, fault), mode, "
        "goal, fault, speed",
        role="state",
    ),
    TopicSpec(
        "/scan",
        "sensor_msgs/msg/LaserScan",
        10,
        "/lidar_driver",
        "",
        "360 beams, 25 m range",
        role="state",
        qos="sensor_data",
    ),
    TopicSpec(
        "/obstacles",
        "astiop_msgs/msg/ObstacleArray",
        2,
        "/obstacle_detector",
        "",
        "obstacles seen in the scan: count, kind, distance, bearing, position",
        role="state",
    ),
    TopicSpec(
        "/diagnostics",
        "diagnostic_msgs/msg/DiagnosticArray",
        1,
        "/astibot_base",
        "",
        "health of motors, lidar, battery, conveyor",
        role="record",
    ),
    TopicSpec(
        "/conveyor/status",
        "astiop_msgs/msg/ConveyorStatus",
        2,
        "/conveyor_plc",
        "",
        "belt running, direction, loaded, both load sensors, lamp",
        role="state",
    ),
    TopicSpec(
        "/plan",
        "nav_msgs/msg/Path",
        1,
        "/navigator",
        "",
        "the global path while navigating",
        role="state",
    ),
    TopicSpec(
        "/camera/image_raw",
        "sensor_msgs/msg/Image",
        5,
        "/camera_driver",
        "",
        "the front camera: 160 x 120 px, rgb8",
        qos="sensor_data",
    ),
    TopicSpec(
        "/camera/image_raw/compressed",
        "sensor_msgs/msg/CompressedImage",
        5,
        "/camera_driver",
        "",
        "the front camera's frames as PNG",
        qos="sensor_data",
    ),
    TopicSpec(
        "/tf",
        "tf2_msgs/msg/TFMessage",
        50,
        "/astibot_base",
        "",
        "map -> odom -> base_link",
        role="record",
    ),
    TopicSpec(
        "/tf_static",
        "tf2_msgs/msg/TFMessage",
        0,
        "/astibot_base",
        "",
        "base_link -> laser, camera",
        qos="transient_local",
    ),
]

_SERVICES = [
    ServiceSpec(
        "/goto_position",
        "astiop_msgs/srv/GotoPosition",
        "/navigator",
        True,
        "go to a named location {name: 'shipping'} or to {x, y, theta}",
        starts_job=True,
    ),
    ServiceSpec(
        "/stop",
        "std_srvs/srv/Trigger",
        "/navigator",
        True,
        # the robot then holds until /release, which the model never learns of (this text
        # is in its prompt; /release is the operator's, agent/tools.py OPERATOR_ONLY)
        "stop motion and cancel the goal; acknowledges a collision fault",
        needs_confirmation=False,
    ),
    ServiceSpec(
        RELEASE,
        "std_srvs/srv/Trigger",
        "/navigator",
        True,
        "release the latched stop (after /stop or the E-STOP): the robot may move again",
    ),
    ServiceSpec(
        "/dock",
        "std_srvs/srv/Trigger",
        "/navigator",
        True,
        "drive onto the charging dock",
        starts_job=True,
    ),
    ServiceSpec(
        "/undock", "std_srvs/srv/Trigger", "/navigator", True, "back off the dock", starts_job=True
    ),
    ServiceSpec(
        "/conveyor/load",
        "std_srvs/srv/Trigger",
        "/conveyor_plc",
        True,
        "take a load on, only at a conveyor station",
        starts_job=True,
    ),
    ServiceSpec(
        "/conveyor/unload",
        "std_srvs/srv/Trigger",
        "/conveyor_plc",
        True,
        "hand the load over, only at a conveyor station",
        starts_job=True,
    ),
    ServiceSpec(
        "/save_location",
        "astiop_msgs/srv/SaveLocation",
        "/astiop_agent",
        True,
        "name the robot's current pose",
    ),
    ServiceSpec(
        "/list_locations",
        "astiop_msgs/srv/ListLocations",
        "/astiop_agent",
        False,
        "names and poses of the named locations",
    ),
]

_ACTIONS = [
    ActionSpec(
        "/navigate_to_pose",
        "nav2_msgs/action/NavigateToPose",
        "/navigator",
        "drive to a pose; feedback: distance remaining",
    ),
]

_NODES = (
    "/astibot_base",
    "/lidar_driver",
    "/camera_driver",
    "/battery_monitor",
    "/navigator",
    "/obstacle_detector",
    "/conveyor_plc",
    "/astiop_agent",
)

_PARAMS = [
    ParamSpec("/astibot_base", "max_linear_speed", 0.8, True, 0.05, 1.4, "m/s"),
    ParamSpec("/astibot_base", "max_angular_speed", 1.0, True, 0.1, 3.0, "rad/s"),
    ParamSpec("/astibot_base", "wheel_radius", 0.0762, description="m"),
    ParamSpec("/lidar_driver", "frequency", 10.0, description="Hz"),
    ParamSpec("/lidar_driver", "range_max", 25.0, description="m"),
    ParamSpec("/navigator", "goal_tolerance", 0.03, description="m"),
    ParamSpec("/navigator", "inflation_radius", 0.72, description="m"),
    ParamSpec("/battery_monitor", "capacity_ah", 22.0),
]


CAMERA_TOPICS = ("/camera/image_raw", "/camera/image_raw/compressed")


def astibot_catalog(*, camera: bool = True) -> Catalog:
    """`camera` False: an ASTIbot without its camera (its topics and driver absent)."""
    from astiop.ros2.profile import match_profile

    cat = Catalog(
        topics={t.name: t for t in _TOPICS if camera or t.name not in CAMERA_TOPICS},
        services={s.name: s for s in _SERVICES},
        actions={a.name: a for a in _ACTIONS},
        nodes=_NODES if camera else tuple(n for n in _NODES if n != "/camera_driver"),
        params={(p.node, p.name): p for p in _PARAMS},
    )
    cat.profile = match_profile(cat)
    return cat
