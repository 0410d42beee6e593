"""ROS 2 interface definitions the robot graph speaks, in the .msg/.srv/.action text format.

Standard types follow their upstream definitions (Humble/Jazzy), with long comments shortened;
`astiop_msgs` holds the project's own types where no standard one fits.
"""

DEFINITIONS: dict[str, str] = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Header": """\
# Standard metadata for higher-level stamped data types.
builtin_interfaces/Time stamp
string frame_id
""",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/Pose2D": """\
# Deprecated upstream but still shipped; the robot's pose in the map frame.
float64 x
float64 y
float64 theta
""",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/msg/TwistStamped": """\
# A twist with reference coordinate frame and timestamp
std_msgs/Header header
Twist twist
""",
    "geometry_msgs/msg/Twist": """\
# This expresses velocity in free space broken into its linear and angular parts.

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
# This represents an estimate of a position and velocity in free space.
std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
""",
    "nav_msgs/msg/Path": """\
# An array of poses that represents a Path for a robot to follow.
std_msgs/Header header
geometry_msgs/PoseStamped[] poses
""",
    "sensor_msgs/msg/LaserScan": """\
# Single scan from a planar laser range-finder
std_msgs/Header header
float32 angle_min        # start angle of the scan [rad]
float32 angle_max        # end angle of the scan [rad]
float32 angle_increment  # angular distance between measurements [rad]
float32 time_increment   # time between measurements [seconds]
float32 scan_time        # time between scans [seconds]
float32 range_min        # minimum range value [m]
float32 range_max        # maximum range value [m]
float32[] ranges         # range data [m]
float32[] intensities    # intensity data [device-specific units]
""",
    "sensor_msgs/msg/BatteryState": """\
uint8 POWER_SUPPLY_STATUS_UNKNOWN = 0
uint8 POWER_SUPPLY_STATUS_CHARGING = 1
uint8 POWER_SUPPLY_STATUS_DISCHARGING = 2
uint8 POWER_SUPPLY_STATUS_NOT_CHARGING = 3
uint8 POWER_SUPPLY_STATUS_FULL = 4
uint8 POWER_SUPPLY_HEALTH_UNKNOWN = 0
uint8 POWER_SUPPLY_HEALTH_GOOD = 1
uint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN = 0
std_msgs/Header  header
float32 voltage          # Voltage in Volts (Mandatory)
float32 temperature      # Temperature in Degrees Celsius (If unmeasured NaN)
float32 current          # Negative when discharging (A)  (If unmeasured NaN)
float32 charge           # Current charge in Ah  (If unmeasured NaN)
float32 capacity         # Capacity in Ah (last full capacity)  (If unmeasured NaN)
float32 design_capacity  # Capacity in Ah (design capacity)  (If unmeasured NaN)
float32 percentage       # Charge percentage on 0 to 1 range  (If unmeasured NaN)
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
bool success   # indicate successful run of triggered service
string message # informational, e.g. for error messages
""",
    "nav2_msgs/action/NavigateToPose": """\
#goal definition
geometry_msgs/PoseStamped pose
string behavior_tree
---
#result definition
uint16 error_code
string error_msg
---
#feedback definition
geometry_msgs/PoseStamped current_pose
builtin_interfaces/Duration navigation_time
builtin_interfaces/Duration estimated_time_remaining
int16 number_of_recoveries
float32 distance_remaining
""",
    "astiop_msgs/msg/RobotStatus": """\
# state: idle, navigating, docking, charging, blocked, e_stopped, fault
std_msgs/Header header
string state
string mode          # auto or manual
string active_goal   # name or coordinates of the goal, empty when none
string fault         # empty when healthy
float64 speed        # m/s, linear
bool e_stopped
bool docked
""",
    "astiop_msgs/msg/Obstacle": """\
string kind          # person, pallet, forklift, unknown
float64 distance     # m, nearest point
float64 bearing      # rad, robot frame, counter-clockwise from ahead
geometry_msgs/Point position  # map frame
float64 size         # m
""",
    "astiop_msgs/msg/ObstacleArray": """\
std_msgs/Header header
uint32 count
Obstacle[] obstacles
""",
    "astiop_msgs/msg/ConveyorStatus": """\
std_msgs/Header header
bool running
int8 direction        # 1 loading, -1 unloading, 0 stopped
bool loaded
bool load_sensor_entry
bool load_sensor_seated
string lamp           # green, green_flashing, yellow, blue, red
""",
    "astiop_msgs/srv/GotoPosition": """\
# Either a named location, or coordinates in the map frame (theta in rad).
string name
float64 x
float64 y
float64 theta
---
bool success
string message
""",
    "astiop_msgs/srv/SaveLocation": """\
# Names the robot's current pose.
string name
string description
---
bool success
string message
""",
    "astiop_msgs/srv/ListLocations": """\
---
string[] names
geometry_msgs/Pose2D[] poses
""",
}
