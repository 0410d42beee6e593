"""The roles a robot's names may play (pose, battery, velocity_command, ...): how each is found on
its graph, by type first, then by conventional names."""

from __future__ import annotations

from dataclasses import dataclass

POSE2D = "geometry_msgs/msg/Pose2D"
AMCL_POSE = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOMETRY = "nav_msgs/msg/Odometry"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
TRIGGER = "std_srvs/srv/Trigger"
NAVIGATE_TO_POSE = "nav2_msgs/action/NavigateToPose"
TF = "tf2_msgs/msg/TFMessage"
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
TF_ROLES = ("transforms", "static_transforms")  # watched only for a pose that needs them


@dataclass(frozen=True)
class Role:
    """How one role is found: the kinds and types that may play it (in order of preference),
    names preferred among several candidates, and names that never play it."""

    name: str
    kinds: tuple[tuple[str, str], ...]  # (topic | service | action, type), best first
    names: tuple[str, ...] = ()  # conventional names, best first, without the namespace
    never: tuple[str, ...] = ()  # a name holding one of these words is not a candidate
    state: bool = False  # the live state is built from it: watched, recorded
    by_name_only: bool = False  # its type is too common (Trigger): only its names play it
    optional: bool = False  # a robot without it lacks nothing (a camera): never "missing"
    description: str = ""


ROLES: tuple[Role, ...] = (
    Role(
        "pose",
        (("topic", POSE2D), ("topic", AMCL_POSE), ("topic", TF), ("topic", ODOMETRY)),
        ("/robot_pose", "/amcl_pose", "/pose", "/tf", "/odom"),
        never=("initial", "goal", "static"),
        state=True,
        description="where the robot is in the map",
    ),
    Role("odometry", (("topic", ODOMETRY),), ("/odom",), state=True, description="velocity"),
    Role(
        "transforms",
        (("topic", TF),),
        ("/tf",),
        state=True,
        by_name_only=True,
        description="map → odom → base: the map pose between a localiser's updates",
    ),
    Role("static_transforms", (("topic", TF),), ("/tf_static",), state=True, by_name_only=True),
    Role(
        "battery",
        (("topic", "sensor_msgs/msg/BatteryState"),),
        ("/battery_status", "/battery_state", "/battery"),
        state=True,
        description="charge, voltage, current",
    ),
    Role(
        "scan",
        (("topic", "sensor_msgs/msg/LaserScan"),),
        ("/scan",),
        never=("filtered_out",),
        state=True,
        description="the lidar",
    ),
    Role(
        "map",
        (("topic", "nav_msgs/msg/OccupancyGrid"),),
        ("/map",),
        never=("costmap", "updates"),
        description="the occupancy grid the robot navigates on",
    ),
    Role(
        "velocity_command",
        (("topic", TWIST), ("topic", TWIST_STAMPED)),
        ("/cmd_vel",),
        never=("_nav", "smoothed", "teleop", "unstamped"),
        description="drives the base",
    ),
    Role(
        "navigation",
        (
            ("action", NAVIGATE_TO_POSE),
            ("service", "astiop_msgs/srv/GotoPosition"),
            ("topic", "geometry_msgs/msg/PoseStamped"),
        ),
        ("/navigate_to_pose", "/goto_position", "/goal_pose"),
        never=("initial", "waypoint", "through"),
        description="sends the robot to a pose",
    ),
    Role(
        "plan",
        (("topic", "nav_msgs/msg/Path"),),
        ("/plan",),
        never=("local", "received", "unsmoothed", "transformed"),
        state=True,
    ),
    Role("stop", (("service", TRIGGER),), ("/stop",), by_name_only=True, description="stops"),
    Role("release", (("service", TRIGGER),), ("/release",), by_name_only=True),
    Role(
        "estop_lock",
        (("topic", "std_msgs/msg/Bool"),),
        ("/e_stop", "/estop", "/emergency_stop"),
        by_name_only=True,
        optional=True,  # said by `astiop doctor` on its own line: what holds the robot
        description="the robot's own E-STOP or lock input (a twist_mux lock): held true while "
        "the E-STOP latches",
    ),
    Role(
        "dock",
        (("service", TRIGGER), ("action", "nav2_msgs/action/DockRobot")),
        ("/dock", "/dock_robot"),
        by_name_only=True,
    ),
    Role(
        "undock",
        (("service", TRIGGER), ("action", "nav2_msgs/action/UndockRobot")),
        ("/undock", "/undock_robot"),
        by_name_only=True,
    ),
    Role(
        "status",
        (("topic", "astiop_msgs/msg/RobotStatus"),),
        ("/robot_status",),
        state=True,
        description="state, mode, goal, fault, speed",
    ),
    Role(
        "diagnostics",
        (("topic", "diagnostic_msgs/msg/DiagnosticArray"),),
        ("/diagnostics",),
        never=("agg", "toplevel"),
        description="health and faults",
    ),
    Role("obstacles", (("topic", "astiop_msgs/msg/ObstacleArray"),), ("/obstacles",), state=True),
    Role(
        "conveyor",
        (("topic", "astiop_msgs/msg/ConveyorStatus"),),
        ("/conveyor/status",),
        state=True,
    ),
    Role(
        "camera",
        (("topic", IMAGE), ("topic", COMPRESSED_IMAGE)),
        (
            "/camera/image_raw",
            "/image_raw",
            "/camera/image_raw/compressed",
            "/image_raw/compressed",
        ),
        never=("depth", "theora", "zstd", "/ir/"),
        optional=True,
        description="the camera's images (read as their size and encoding, not their pixels)",
    ),
    Role("save_location", (("service", "astiop_msgs/srv/SaveLocation"),), ("/save_location",)),
    Role("list_locations", (("service", "astiop_msgs/srv/ListLocations"),), ("/list_locations",)),
)
ROLE_NAMES = tuple(r.name for r in ROLES)
ROLE_BY_NAME = {r.name: r for r in ROLES}
