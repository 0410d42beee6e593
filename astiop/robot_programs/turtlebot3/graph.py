"""The ROS 2 graph a TurtleBot3 under Nav2 presents, as upstream has it: nodes, and each topic,
service and action with its type, the node that owns it and its QoS. Names are relative to the
robot's namespace ("" or "/tb3_1").

Read from (jazzy and humble branches):
- ROBOTIS-GIT/turtlebot3: turtlebot3_node/src/{turtlebot3,diff_drive_controller,odometry}.cpp,
  sensors/*.cpp, devices/*.cpp, include/turtlebot3_node/twist_subscriber.hpp;
  turtlebot3_bringup/launch/{robot,turtlebot3_state_publisher}.launch.py (LDS-01 by default:
  hls_lfcd_lds_driver's hlds_laser_publisher); turtlebot3_bringup/param/[humble/]*.yaml
  (enable_stamped_cmd_vel true on jazzy, false on humble).
- ROBOTIS-GIT/hls_lfcd_lds_driver: src/hlds_laser_publisher.cpp (/scan, SensorDataQoS).
- ros-navigation/navigation2: nav2_bringup/launch/{navigation,localization}_launch.py (the
  lifecycle nodes, cmd_vel -> cmd_vel_nav remaps), nav2_amcl/src/amcl_node.cpp,
  nav2_map_server/src/map_server/map_server.cpp, nav2_lifecycle_manager/src/lifecycle_manager.cpp,
  nav2_planner/src/planner_server.cpp, nav2_controller/src/controller_server.cpp,
  nav2_velocity_smoother/src/velocity_smoother.cpp, nav2_collision_monitor/src/
  collision_monitor_node.cpp, nav2_bt_navigator/src/navigators/navigate_to_pose.cpp,
  nav2_behavior_tree/include/nav2_behavior_tree/bt_action_server_impl.hpp (the
  <node>_<action>_rclcpp_node client nodes), nav2_costmap_2d/src/costmap_2d_ros.cpp.
  nav2_costmap_2d/src/{costmap_2d_publisher,clear_costmap_service}.cpp, nav2_util/src/
  lifecycle_node.cpp (the bond), nav2_behavior_tree/.../ros_topic_logger.hpp.
Not listed: route_server's graph topic, costmap layers' own topics (voxel_layer's
voxel_marked_cloud ...), the DWB controller's debug topics; rclpy adds each node's parameter
services and /rosout itself.
"""

from __future__ import annotations

from dataclasses import dataclass

DISTROS = ("jazzy", "humble")
MODELS = ("burger", "waffle")


@dataclass(frozen=True)
class Endpoint:
    kind: str  # pub | sub | srv | action
    name: str
    type: str
    node: str
    qos: str = ""  # "" reliable depth 10 | sensor_data | transient_local


TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
TF = "tf2_msgs/msg/TFMessage"


def cmd_vel_type(distro: str) -> str:
    """TurtleBot3's bringup sets enable_stamped_cmd_vel: true on jazzy, false on humble."""
    return TWIST_STAMPED if distro == "jazzy" else TWIST


def lifecycle_nodes(distro: str) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """Each lifecycle manager and the nodes it brings up, in order (nav2_bringup's launch)."""
    navigation = ["controller_server", "smoother_server", "planner_server"]
    if distro == "jazzy":
        navigation += ["route_server", "behavior_server", "velocity_smoother"]
        navigation += ["collision_monitor", "bt_navigator", "waypoint_follower", "docking_server"]
    else:
        navigation += ["behavior_server", "bt_navigator", "waypoint_follower", "velocity_smoother"]
    return (
        ("lifecycle_manager_localization", ("map_server", "amcl")),
        ("lifecycle_manager_navigation", tuple(navigation)),
    )


COSTMAPS = ("global_costmap/global_costmap", "local_costmap/local_costmap")
CAMERA_TOPIC = "/camera/image_raw"


def camera_node(distro: str, model: str) -> str | None:
    """Who publishes the Waffle's camera (a burger has none), as ROBOTIS-GIT/
    turtlebot3_simulations has it: turtlebot3_gazebo/models/turtlebot3_waffle/model.sdf's camera
    sensor (camera_rgb_frame); on humble its gazebo_ros_camera plugin "camera_driver" (camera
    name "camera"), on jazzy ros_gz_image's image_bridge (launch/spawn_turtlebot3.launch.py,
    started for every model but the burger)."""
    if model == "burger":
        return None
    return "image_bridge" if distro == "jazzy" else "camera_driver"


def node_names(distro: str, model: str = "burger") -> tuple[str, ...]:
    names = ["turtlebot3_node", "diff_drive_controller", "robot_state_publisher"]
    names.append("hlds_laser_publisher")
    if (camera := camera_node(distro, model)) is not None:
        names.append(camera)
    for manager, managed in lifecycle_nodes(distro):
        names += [*managed, manager]
    names += COSTMAPS
    names += ["bt_navigator_navigate_to_pose_rclcpp_node"]
    names += ["bt_navigator_navigate_through_poses_rclcpp_node"]
    return tuple(names)


BOND = "bond/msg/Status"


def _lifecycle(node: str) -> list[Endpoint]:
    """rclcpp_lifecycle's services and transition topic on every Nav2 server, and its bond to
    the lifecycle manager."""
    pre = f"/{node}"
    out = [Endpoint("pub", f"{pre}/transition_event", "lifecycle_msgs/msg/TransitionEvent", node)]
    out += [Endpoint("pub", "/bond", BOND, node), Endpoint("sub", "/bond", BOND, node)]
    for verb, type_ in (
        ("change_state", "ChangeState"),
        ("get_state", "GetState"),
        ("get_available_states", "GetAvailableStates"),
        ("get_available_transitions", "GetAvailableTransitions"),
        ("get_transition_graph", "GetAvailableTransitions"),
    ):
        out.append(Endpoint("srv", f"{pre}/{verb}", f"lifecycle_msgs/srv/{type_}", node))
    return out


def endpoints(distro: str, model: str = "burger") -> tuple[Endpoint, ...]:
    cmd = cmd_vel_type(distro)
    e = Endpoint
    camera = camera_node(distro, model)
    out = [e("pub", CAMERA_TOPIC, "sensor_msgs/msg/Image", camera)] if camera else []
    out += [
        # turtlebot3_node (Sensors' qos_: KeepLast(10), reliable)
        e("sub", "/cmd_vel", cmd, "turtlebot3_node"),
        e("pub", "/battery_state", "sensor_msgs/msg/BatteryState", "turtlebot3_node"),
        e("pub", "/imu", "sensor_msgs/msg/Imu", "turtlebot3_node"),
        e("pub", "/magnetic_field", "sensor_msgs/msg/MagneticField", "turtlebot3_node"),
        e("pub", "/sensor_state", "turtlebot3_msgs/msg/SensorState", "turtlebot3_node"),
        e("pub", "/joint_states", "sensor_msgs/msg/JointState", "turtlebot3_node"),
        e("srv", "/motor_power", "std_srvs/srv/SetBool", "turtlebot3_node"),
        e("srv", "/reset", "std_srvs/srv/Trigger", "turtlebot3_node"),
        e("srv", "/sound", "turtlebot3_msgs/srv/Sound", "turtlebot3_node"),
        # diff_drive_controller: odometry (use_imu: true syncs joint_states with imu)
        e("pub", "/odom", "nav_msgs/msg/Odometry", "diff_drive_controller"),
        e("pub", "/tf", TF, "diff_drive_controller"),
        e("sub", "/joint_states", "sensor_msgs/msg/JointState", "diff_drive_controller"),
        e("sub", "/imu", "sensor_msgs/msg/Imu", "diff_drive_controller"),
        e("srv", "/reset_odometry", "std_srvs/srv/Trigger", "diff_drive_controller"),
        # robot_state_publisher
        e("pub", "/robot_description", "std_msgs/msg/String", "robot_state_publisher", "transient_local"),
        e("pub", "/tf_static", TF, "robot_state_publisher", "transient_local"),
        e("pub", "/tf", TF, "robot_state_publisher"),
        e("sub", "/joint_states", "sensor_msgs/msg/JointState", "robot_state_publisher", "sensor_data"),
        # the LDS-01 driver
        e("pub", "/scan", "sensor_msgs/msg/LaserScan", "hlds_laser_publisher", "sensor_data"),
        # map_server, amcl
        e("pub", "/map", "nav_msgs/msg/OccupancyGrid", "map_server", "transient_local"),
        e("srv", "/map_server/map", "nav_msgs/srv/GetMap", "map_server"),
        e("srv", "/map_server/load_map", "nav2_msgs/srv/LoadMap", "map_server"),
        e("pub", "/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", "amcl", "transient_local"),
        e("pub", "/particle_cloud", "nav2_msgs/msg/ParticleCloud", "amcl", "sensor_data"),
        e("pub", "/tf", TF, "amcl"),
        e("sub", "/map", "nav_msgs/msg/OccupancyGrid", "amcl", "transient_local"),
        e("sub", "/scan", "sensor_msgs/msg/LaserScan", "amcl", "sensor_data"),
        e("sub", "/initialpose", "geometry_msgs/msg/PoseWithCovarianceStamped", "amcl"),
        e("srv", "/reinitialize_global_localization", "std_srvs/srv/Empty", "amcl"),
        e("srv", "/request_nomotion_update", "std_srvs/srv/Empty", "amcl"),
        e("srv", "/set_initial_pose", "nav2_msgs/srv/SetInitialPose", "amcl"),
        # planner, controller, behaviors, smoother, waypoints, navigator
        e("pub", "/plan", "nav_msgs/msg/Path", "planner_server"),
        e("action", "/compute_path_to_pose", "nav2_msgs/action/ComputePathToPose", "planner_server"),
        e("action", "/compute_path_through_poses", "nav2_msgs/action/ComputePathThroughPoses", "planner_server"),
        e("srv", "/is_path_valid", "nav2_msgs/srv/IsPathValid", "planner_server"),
        e("pub", "/cmd_vel_nav", cmd, "controller_server"),
        e("action", "/follow_path", "nav2_msgs/action/FollowPath", "controller_server"),
        e("sub", "/speed_limit", "nav2_msgs/msg/SpeedLimit", "controller_server"),
        e("pub", "/cmd_vel_nav", cmd, "behavior_server"),
        e("action", "/spin", "nav2_msgs/action/Spin", "behavior_server"),
        e("action", "/backup", "nav2_msgs/action/BackUp", "behavior_server"),
        e("action", "/drive_on_heading", "nav2_msgs/action/DriveOnHeading", "behavior_server"),
        e("action", "/wait", "nav2_msgs/action/Wait", "behavior_server"),
        e("action", "/smooth_path", "nav2_msgs/action/SmoothPath", "smoother_server"),
        e("action", "/follow_waypoints", "nav2_msgs/action/FollowWaypoints", "waypoint_follower"),
        e("action", "/navigate_to_pose", "nav2_msgs/action/NavigateToPose", "bt_navigator"),
        e("action", "/navigate_through_poses", "nav2_msgs/action/NavigateThroughPoses", "bt_navigator"),
        e("sub", "/goal_pose", "geometry_msgs/msg/PoseStamped", "bt_navigator"),
        e("pub", "/behavior_tree_log", "nav2_msgs/msg/BehaviorTreeLog", "bt_navigator"),
        e("sub", "/odom", "nav_msgs/msg/Odometry", "bt_navigator"),
        e("sub", "/cmd_vel_nav", cmd, "velocity_smoother"),
    ]  # fmt: skip
    if distro == "jazzy":
        out += [
            e("action", "/assisted_teleop", "nav2_msgs/action/AssistedTeleop", "behavior_server"),
            e("pub", "/cmd_vel_smoothed", cmd, "velocity_smoother"),
            e("sub", "/cmd_vel_smoothed", cmd, "collision_monitor"),
            e("pub", "/cmd_vel", cmd, "collision_monitor"),
            e("pub", "/collision_monitor_state", "nav2_msgs/msg/CollisionMonitorState", "collision_monitor"),
            e("srv", "/collision_monitor/toggle", "nav2_msgs/srv/Toggle", "collision_monitor"),
            e("action", "/dock_robot", "nav2_msgs/action/DockRobot", "docking_server"),
            e("action", "/undock_robot", "nav2_msgs/action/UndockRobot", "docking_server"),
            e("action", "/compute_route", "nav2_msgs/action/ComputeRoute", "route_server"),
            e("action", "/compute_and_track_route", "nav2_msgs/action/ComputeAndTrackRoute", "route_server"),
            e("srv", "/route_server/set_route_graph", "nav2_msgs/srv/SetRouteGraph", "route_server"),
        ]  # fmt: skip
    else:  # humble's bringup remaps the smoother's cmd_vel_smoothed to cmd_vel
        out.append(e("pub", "/cmd_vel", cmd, "velocity_smoother"))
    for manager, managed in lifecycle_nodes(distro):
        out += [
            e("srv", f"/{manager}/manage_nodes", "nav2_msgs/srv/ManageLifecycleNodes", manager),
            e("srv", f"/{manager}/is_active", "std_srvs/srv/Trigger", manager),
            e("pub", "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", manager),
            e("pub", "/bond", BOND, manager),
            e("sub", "/bond", BOND, manager),
        ]
        for node in managed:
            out += _lifecycle(node)
    for costmap in COSTMAPS:
        name = costmap.split("/")[0]
        ns, latched = f"/{name}", "transient_local"
        out += [
            e("pub", f"{ns}/costmap", "nav_msgs/msg/OccupancyGrid", costmap, latched),
            e("pub", f"{ns}/costmap_raw", "nav2_msgs/msg/Costmap", costmap, latched),
            e("pub", f"{ns}/costmap_updates", "map_msgs/msg/OccupancyGridUpdate", costmap, latched),
            e("pub", f"{ns}/published_footprint", "geometry_msgs/msg/PolygonStamped", costmap),
            e("sub", f"{ns}/footprint", "geometry_msgs/msg/Polygon", costmap),
            e("srv", f"{ns}/get_costmap", "nav2_msgs/srv/GetCostmap", costmap),
            e("srv", f"{ns}/clear_except_{name}", "nav2_msgs/srv/ClearCostmapExceptRegion", costmap),
            e("srv", f"{ns}/clear_around_{name}", "nav2_msgs/srv/ClearCostmapAroundRobot", costmap),
            e("srv", f"{ns}/clear_entirely_{name}", "nav2_msgs/srv/ClearEntireCostmap", costmap),
        ]  # fmt: skip
        if distro == "jazzy":
            out += [
                e("pub", f"{ns}/costmap_raw_updates", "nav2_msgs/msg/CostmapUpdate", costmap, latched),
                e("srv", f"{ns}/clear_around_pose_{name}", "nav2_msgs/srv/ClearCostmapAroundPose", costmap),
                e("srv", f"{ns}/get_cost_{name}", "nav2_msgs/srv/GetCost", costmap),
            ]  # fmt: skip
        out += _lifecycle(costmap)
    return tuple(out)
