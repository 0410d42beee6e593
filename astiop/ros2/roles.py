"""The roles a robot's names may play (pose, battery, velocity_command, ...), each one definition:
how it is found on its graph (by type first, then by conventional names), and what the layers
above make of it (its label in answers, the words that ask for it, the tool that reads it, how it
is summarised). The profile, the state, the agent, MCP and missions read it from here; the
agent-level parts are plain data, as this vocabulary imports nothing above it."""

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
    # what the agent makes of it. A reading is keyed by its first name (the ASTIbot's own).
    label: str = ""  # what an answer calls its reading; "": the agent does not read it out
    words: str = ""  # a request's words (regex) that ask for its reading
    rank: int = 50  # among roles whose words a request holds, the lowest rank is read
    tool: str = ""  # the short name of the model's tool that reads it (an operator's word)
    readable: bool = True  # False: a command, or too big to read out: no tool reads it
    stands_in: str = ""  # the role whose reading answers for it on a robot without it
    sized: tuple[str, ...] = ()  # fields read as their size (`<field>_bytes`), never kept
    summary: tuple[str, ...] = ()  # one line from its values: the first template they fill
    # the fields an operator asks about, each with its words (regex), in the order tried
    fields: tuple[tuple[str, str], ...] = ()
    named_by: str = ""  # the words that name it in such a question ("the lidar's range")

    @property
    def key(self) -> str:
        """The reader's name for its reading: its first conventional name (the ASTIbot's)."""
        return self.names[0] if self.names else ""


ROLES: tuple[Role, ...] = (
    Role(
        "pose",
        (("topic", POSE2D), ("topic", AMCL_POSE), ("topic", TF), ("topic", ODOMETRY)),
        ("/robot_pose", "/amcl_pose", "/pose", "/tf", "/odom"),
        never=("initial", "goal", "static"),
        state=True,
        description="where the robot is in the map",
        label="pose",
        words=r"where|position|location|pose|coordinates|heading|locate|find the robot|"
        r"x and y|part of the floor",
        rank=90,
        tool="where",
        fields=(
            ("x", r"\bx[- ]?(?:coordinate|position|value)\b"),
            ("y", r"\by[- ]?(?:coordinate|position|value)\b"),
            (
                "heading",
                r"facing|heading|direction|orientation|\byaw\b|pointing|which way|compass|"
                r"(?:robot's|its|your) bearing|bearing of (?:the robot|it)",
            ),
        ),
    ),
    Role(
        "odometry",
        (("topic", ODOMETRY),),
        ("/odom",),
        state=True,
        description="velocity",
        label="odometry",
        words=r"how fast|speed|velocity|moving|odometry|odom",
        rank=80,
        tool="speed",
        fields=(
            (
                "angular",
                r"angular (?:velocity|speed)|turn(?:ing)? rate|yaw rate|"
                r"(?:is it|is the robot) (?:rotating|spinning|turning)",
            ),
        ),
    ),
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
        label="battery state",
        words=r"battery|charge|charged|charging|juice|power|voltage|percent|energy",
        rank=20,
        tool="battery",
        fields=(
            (
                "time_to_full",
                r"(?:how (?:long|much longer)|time|when|until|till)\b.*\b(?:full(?:y charged)?|"
                r"charged up|topped up|finish(?:es|ed)? charging|done charging)\b",
            ),
            (
                "time_to_empty",
                r"(?:how long|time|when)\b.*\b(?:empty|run(?:s)? out|battery last|die|dies|"
                r"go(?:es)? flat|be flat|run(?:s)? dry)\b",
            ),
            (
                "temperature",
                r"temp(?:erature)?s?\b|\bhow (?:hot|warm)\b|\boverheat|"
                r"\b(?:getting|running|too|very|gets) (?:hot|warm)\b",
            ),
            ("voltage", r"volt(?:age|s)?\b"),
            (
                "current",
                r"current\b(?!\s+(?:battery|charge|position|pose|location|state|status|speed|goal|"
                r"task|level|percentage|heading|mode|path|plan|route|map|job|mission|time|"
                r"coordinates?|orientation|place|station|area|zone|reading|value|temperature|"
                r"voltage|x|y)\b)|amps?\b(?![- ]?hours?)|amperage",
            ),
            (
                "charge_ah",
                r"(?:charge|left|remaining|stored)\b.{0,25}(?:amp[- ]?hours?|\bah\b)|"
                r"(?:amp[- ]?hours?|\bah\b).{0,25}(?:left|remaining|stored)",
            ),
            ("capacity", r"capacity|amp[- ]?hours?|\bah\b|how big is the battery"),
            ("health", r"(?:battery|pack)(?:'s)? (?:health|condition)|health of the battery"),
            (
                "technology",
                r"chemistry|technology|kind of battery|type of battery|battery type|"
                r"what battery|which battery|lithium|lead",
            ),
        ),
        named_by=r"batter(?:y|ies)|pack|cells?|charg",
    ),
    Role(
        "scan",
        (("topic", "sensor_msgs/msg/LaserScan"),),
        ("/scan",),
        never=("filtered_out",),
        state=True,
        description="the lidar",
        label="laser scan",
        words=r"lidar|laser|scan|range finder",
        rank=40,
        tool="lidar",
        fields=(
            ("frame", r"\b(?:tf )?frame\b"),
            (
                "range_max",
                r"max(?:imum)? range|how far (?:can|does) (?:the )?(?:lidar|laser|scanner|it) "
                r"(?:see|reach|detect|sense|measure)|\brange of\b|lidar(?:'s)? range|\brange\b|"
                r"(?:furthest|farthest|longest|max(?:imum)?) distance|"
                r"(?:up to )?what (?:distance|range)\b.{0,30}\b"
                r"(?:see|reach|detect|sense|measure|pick)",
            ),
            (
                "range_min",
                r"min(?:imum)? range|closest (?:it|the lidar) can|"
                r"(?:shortest|smallest|min(?:imum)?|closest) distance",
            ),
            ("beams", r"beams|rays|how many (?:points|readings|measurements)|resolution"),
            ("rate", r"scan rate|frequency|how often|\bhz\b|refresh"),
            ("fov", r"field of view|\bfov\b|angle|how wide|degrees? (?:does|can)"),
        ),
        named_by=r"lidar|laser|scan(?:ner)?|range ?finder|rangefinder",
    ),
    Role(
        "map",
        (("topic", "nav_msgs/msg/OccupancyGrid"),),
        ("/map",),
        never=("costmap", "updates"),
        description="the occupancy grid the robot navigates on",
        readable=False,
    ),
    Role(
        "velocity_command",
        (("topic", TWIST), ("topic", TWIST_STAMPED)),
        ("/cmd_vel",),
        never=("_nav", "smoothed", "teleop", "unstamped"),
        description="drives the base",
        readable=False,
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
        label="path",
        tool="path",
        readable=False,
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
        label="status report",
        words=r"status|state|doing|busy|idle|docked|navigating|mode|goal|stop|up to|working on|"
        r"task",
        rank=95,  # last: "which way does it face on the dock" asks the pose's heading
        tool="status",
        fields=(
            ("e_stopped", r"e-?stop(?:ped)?|emergency[- ]stop(?:ped)?"),
            ("docked", r"\bdocked\b|\bon (?:the|its) (?:dock|charger)\b|\bplugged in\b"),
        ),
    ),
    Role(
        "diagnostics",
        (("topic", "diagnostic_msgs/msg/DiagnosticArray"),),
        ("/diagnostics",),
        never=("agg", "toplevel"),
        description="health and faults",
        label="diagnostics",
        words=r"diagnos|health|error|fault|warning|motor|problem",
        rank=60,
        tool="diagnostics",
    ),
    Role(
        "obstacles",
        (("topic", "astiop_msgs/msg/ObstacleArray"),),
        ("/obstacles",),
        state=True,
        label="obstacle detection or laser scan",
        words=r"obstacle|blocking|blocked|in the way|(?:the|its|robot's) way|around (?:the robot|"
        r"it|you)|nearby|near it|near the robot|close by|clear|free|obstruct|in front|objects?|"
        r"detect",
        rank=30,
        tool="obstacles",
        stands_in="scan",  # obstacles seen in its scan
    ),
    Role(
        "conveyor",
        (("topic", "astiop_msgs/msg/ConveyorStatus"),),
        ("/conveyor/status",),
        state=True,
        label="conveyor status",
        words=r"conveyor|load sensor|lamp|belt|carrying|loaded|cargo|payload",
        rank=10,
        tool="conveyor",
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
        label="camera image",
        words=r"camera|image|picture|photo|video|webcam",
        rank=0,
        tool="camera",
        sized=("data",),
        summary=(
            "camera image {width} x {height} px, {encoding}, {data_bytes} bytes",
            "camera image, compressed {format}, {data_bytes} bytes",
        ),
    ),
    Role("save_location", (("service", "astiop_msgs/srv/SaveLocation"),), ("/save_location",)),
    Role("list_locations", (("service", "astiop_msgs/srv/ListLocations"),), ("/list_locations",)),
)
ROLE_NAMES = tuple(r.name for r in ROLES)
ROLE_BY_NAME = {r.name: r for r in ROLES}
READ_ROLES = tuple(r for r in ROLES if r.label)  # the roles the agent reads out
KEY_ROLES = {r.key: r.name for r in READ_ROLES}  # the reader's key for a reading -> its role
