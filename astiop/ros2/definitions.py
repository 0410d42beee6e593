"""ROS 2 interface definitions the robot graph speaks, in the .msg/.srv/.action text format.

Standard types state their upstream interface (field names and types, constants and their
values, as `git show humble:` / `jazzy:` of ros2/common_interfaces and navigation2 have them),
written here without upstream's comments: the project ships only what we write. On a real
robot `ros2 interface show` is the robot's own and prints upstream's text. `astiop_msgs` holds
the project's own types where no standard one fits, read from its ament package
(`packages/astiop_msgs`). Where the distros differ, HUMBLE holds
Humble's version; DEFINITIONS is Jazzy's.
"""

import re
from pathlib import Path

# astiop_msgs is a real ament package (built with cmake, or colcon on a robot): its files are
# the definitions.
ASTIOP_MSGS = Path(__file__).parent / "packages" / "astiop_msgs"


def _package_definitions(root: Path) -> dict[str, str]:
    return {
        f"{root.name}/{f.parent.name}/{f.stem}": f.read_text(encoding="utf-8")
        for kind in ("msg", "srv", "action")
        for f in sorted((root / kind).glob(f"*.{kind}"))
    }


DEFINITIONS: dict[str, str] = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Empty": "",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Header": """\
builtin_interfaces/Time stamp
string frame_id
""",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/Pose2D": """\
float64 x
float64 y
float64 theta
""",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/msg/PoseWithCovarianceStamped": "std_msgs/Header header\nPoseWithCovariance pose\n",
    "geometry_msgs/msg/TwistStamped": """\
std_msgs/Header header
Twist twist
""",
    "geometry_msgs/msg/Twist": """\
Vector3  linear
Vector3  angular
""",
    "geometry_msgs/msg/TwistWithCovariance": "Twist twist\nfloat64[36] covariance\n",
    "geometry_msgs/msg/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/msg/TransformStamped": """\
std_msgs/Header header
string child_frame_id
Transform transform
""",
    "nav_msgs/msg/Odometry": """\
std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
""",
    "nav_msgs/msg/Path": """\
std_msgs/Header header
geometry_msgs/PoseStamped[] poses
""",
    "sensor_msgs/msg/LaserScan": """\
std_msgs/Header header
float32 angle_min
float32 angle_max
float32 angle_increment
float32 time_increment
float32 scan_time
float32 range_min
float32 range_max
float32[] ranges
float32[] intensities
""",
    "sensor_msgs/msg/Image": """\
std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
""",
    "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n",
    "sensor_msgs/msg/BatteryState": """\
uint8 POWER_SUPPLY_STATUS_UNKNOWN = 0
uint8 POWER_SUPPLY_STATUS_CHARGING = 1
uint8 POWER_SUPPLY_STATUS_DISCHARGING = 2
uint8 POWER_SUPPLY_STATUS_NOT_CHARGING = 3
uint8 POWER_SUPPLY_STATUS_FULL = 4
uint8 POWER_SUPPLY_HEALTH_UNKNOWN = 0
uint8 POWER_SUPPLY_HEALTH_GOOD = 1
uint8 POWER_SUPPLY_HEALTH_OVERHEAT = 2
uint8 POWER_SUPPLY_HEALTH_DEAD = 3
uint8 POWER_SUPPLY_HEALTH_OVERVOLTAGE = 4
uint8 POWER_SUPPLY_HEALTH_UNSPEC_FAILURE = 5
uint8 POWER_SUPPLY_HEALTH_COLD = 6
uint8 POWER_SUPPLY_HEALTH_WATCHDOG_TIMER_EXPIRE = 7
uint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE = 8
uint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN = 0
uint8 POWER_SUPPLY_TECHNOLOGY_NIMH = 1
uint8 POWER_SUPPLY_TECHNOLOGY_LION = 2
uint8 POWER_SUPPLY_TECHNOLOGY_LIPO = 3
uint8 POWER_SUPPLY_TECHNOLOGY_LIFE = 4
uint8 POWER_SUPPLY_TECHNOLOGY_NICD = 5
uint8 POWER_SUPPLY_TECHNOLOGY_LIMN = 6
uint8 POWER_SUPPLY_TECHNOLOGY_TERNARY = 7
uint8 POWER_SUPPLY_TECHNOLOGY_VRLA = 8
std_msgs/Header  header
float32 voltage
float32 temperature
float32 current
float32 charge
float32 capacity
float32 design_capacity
float32 percentage
uint8   power_supply_status
uint8   power_supply_health
uint8   power_supply_technology
bool    present
float32[] cell_voltage
float32[] cell_temperature
string location
string serial_number
""",
    "diagnostic_msgs/msg/KeyValue": "string key\nstring value\n",
    "diagnostic_msgs/msg/DiagnosticStatus": """\
byte OK=0
byte WARN=1
byte ERROR=2
byte STALE=3
byte level
string name
string message
string hardware_id
KeyValue[] values
""",
    "diagnostic_msgs/msg/DiagnosticArray": "std_msgs/Header header\nDiagnosticStatus[] status\n",
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "std_srvs/srv/Trigger": """\
---
bool success
string message
""",
    # every action server's hidden cancel service (ros2/rcl_interfaces action_msgs, and
    # ros2/unique_identifier_msgs msg/UUID.msg; the same on humble and jazzy): a zero goal id
    # and stamp cancel every goal
    "unique_identifier_msgs/msg/UUID": "uint8[16] uuid\n",
    "action_msgs/msg/GoalInfo": "unique_identifier_msgs/UUID goal_id\nbuiltin_interfaces/Time stamp\n",
    "action_msgs/srv/CancelGoal": """\
GoalInfo goal_info
---
int8 ERROR_NONE=0
int8 ERROR_REJECTED=1
int8 ERROR_UNKNOWN_GOAL_ID=2
int8 ERROR_GOAL_TERMINATED=3
int8 return_code
GoalInfo[] goals_canceling
""",
    "nav2_msgs/action/NavigateToPose": """\
geometry_msgs/PoseStamped pose
string behavior_tree
---
uint16 NONE=0
uint16 error_code
string error_msg
---
geometry_msgs/PoseStamped current_pose
builtin_interfaces/Duration navigation_time
builtin_interfaces/Duration estimated_time_remaining
int16 number_of_recoveries
float32 distance_remaining
""",
    **_package_definitions(ASTIOP_MSGS),
}

# Humble's versions, where Jazzy changed a type.
HUMBLE: dict[str, str] = {
    # no TERNARY (7) or VRLA (8) technology yet
    "sensor_msgs/msg/BatteryState": re.sub(
        r"uint8 POWER_SUPPLY_TECHNOLOGY_(TERNARY|VRLA) = \d\n",
        "",
        DEFINITIONS["sensor_msgs/msg/BatteryState"],
    ),
    # the result was empty; error codes came in Jazzy
    "nav2_msgs/action/NavigateToPose": DEFINITIONS["nav2_msgs/action/NavigateToPose"].replace(
        "uint16 NONE=0\nuint16 error_code\nstring error_msg\n", "std_msgs/Empty result\n"
    ),
}


# Kilted's, where it added to Jazzy's (navigation2's kilted branch)
KILTED: dict[str, str] = {
    "nav2_msgs/action/NavigateToPose": DEFINITIONS["nav2_msgs/action/NavigateToPose"].replace(
        "uint16 NONE=0\n",
        "uint16 NONE=0\nuint16 UNKNOWN=9000\nuint16 FAILED_TO_LOAD_BEHAVIOR_TREE=9001\n"
        "uint16 TF_ERROR=9002\nuint16 TIMEOUT=9003\n",
    ),
}


def definitions(distro: str) -> dict[str, str]:
    """Every known type as `distro` defines it."""
    overrides = {"humble": HUMBLE, "kilted": KILTED}.get(distro, {})
    return {**DEFINITIONS, **overrides} if overrides else DEFINITIONS
