"""The parameters the TurtleBot3's nodes declare here, and its robot description: a table we
write, its values read from upstream (never the files themselves):

- ROBOTIS-GIT/turtlebot3 (jazzy branch): turtlebot3_navigation2/param/{burger,waffle}.yaml and
  param/humble/*.yaml (controller, goal checker, velocity smoother, amcl, bt_navigator,
  costmaps), turtlebot3_bringup/param/[humble/]{burger,waffle}.yaml (turtlebot3_node's wheels
  and enable_stamped_cmd_vel, diff_drive_controller's odometry frames),
  turtlebot3_description/urdf/turtlebot3_{burger,waffle}.urdf (base_link's collision box, the
  wheel, IMU and scan joints);
- turtlebot3_bringup/launch/robot.launch.py (the lidar's frame_id and port);
- ros/robot_state_publisher src/robot_state_publisher.cpp (its own parameters);
- ros-navigation/navigation2 nav2_bringup (the lifecycle managers' node_names, autostart).

A consumer (astiop) reads what matters of these: the speed limits, the footprint, the frames."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from astiop.robot_programs.turtlebot3.graph import lifecycle_nodes, node_names


@dataclass(frozen=True)
class Limits:
    """What the simulated base and its navigator obey, from the parameters above."""

    max_vel_x: float  # controller_server FollowPath.max_vel_x
    max_vel_theta: float
    xy_goal_tolerance: float  # goal_checker (general_goal_checker on humble)
    yaw_goal_tolerance: float
    decel_lim_x: float
    robot_radius: float  # global_costmap
    wheel_separation: float  # turtlebot3_node wheels.separation
    wheel_radius: float


@dataclass(frozen=True)
class Model:
    """One TurtleBot3's figures (m): wheels, the costmaps' radius, base_link's collision box
    (size and offset from base_link), the wheel and scan joints' offsets."""

    separation: float
    radius: float
    robot_radius: dict[str, float]  # by distro
    box: tuple[float, float, float]
    box_at: tuple[float, float, float]
    wheel_y: float
    scan_at: tuple[float, float, float]
    imu_at: tuple[float, float, float]


MODELS = {
    "burger": Model(
        0.160, 0.033, {"jazzy": 0.1, "humble": 0.1}, (0.140, 0.140, 0.143),
        (-0.032, 0.0, 0.070), 0.080, (-0.032, 0.0, 0.172), (-0.032, 0.0, 0.068),
    ),
    "waffle": Model(
        0.287, 0.033, {"jazzy": 0.15, "humble": 0.22}, (0.266, 0.266, 0.094),
        (-0.064, 0.0, 0.047), 0.144, (-0.064, 0.0, 0.122), (0.0, 0.0, 0.068),
    ),
}  # fmt: skip
# FollowPath.max_vel_x: 0.3 on jazzy, 0.22 in the humble files (both models)
MAX_VEL_X = {"jazzy": 0.3, "humble": 0.22}


def frame_prefix(namespace: str) -> str:
    ns = namespace.strip("/")
    return f"{ns}/" if ns else ""


def urdf(model: str, namespace: str) -> str:
    """A robot description of the model's figures (base_footprint -> base_link -> wheels, IMU,
    scan), its frames prefixed with the namespace as the description's xacro does."""
    m, p = MODELS[model], frame_prefix(namespace)

    def xyz(v: tuple[float, float, float]) -> str:
        return " ".join(f"{c:g}" for c in v)

    def fixed(name: str, parent: str, child: str, at: tuple[float, float, float]) -> str:
        return (
            f'<joint name="{p}{name}" type="fixed"><parent link="{p}{parent}"/>'
            f'<child link="{p}{child}"/><origin xyz="{xyz(at)}" rpy="0 0 0"/></joint>'
        )

    wheels = "".join(
        f'<joint name="{p}wheel_{side}_joint" type="continuous"><parent link="{p}base_link"/>'
        f'<child link="{p}wheel_{side}_link"/><origin xyz="0 {y:g} 0.023" rpy="-1.57 0 0"/>'
        f'<axis xyz="0 0 1"/></joint><link name="{p}wheel_{side}_link"/>'
        for side, y in (("left", m.wheel_y), ("right", -m.wheel_y))
    )
    return (
        f'<?xml version="1.0" ?><robot name="turtlebot3_{model}">'
        f'<link name="{p}base_footprint"/>'
        + fixed("base_joint", "base_footprint", "base_link", (0.0, 0.0, 0.010))
        + f'<link name="{p}base_link"><collision><origin xyz="{xyz(m.box_at)}" rpy="0 0 0"/>'
        f'<geometry><box size="{xyz(m.box)}"/></geometry></collision></link>'
        + wheels
        + fixed("imu_joint", "base_link", "imu_link", m.imu_at)
        + f'<link name="{p}imu_link"/>'
        + fixed("scan_joint", "base_link", "base_scan", m.scan_at)
        + f'<link name="{p}base_scan"/></robot>'
    )


def node_parameters(distro: str, model: str, namespace: str) -> dict[str, dict[str, Any]]:
    """node name (relative, e.g. "global_costmap/global_costmap") -> parameter -> value."""
    m, prefix = MODELS[model], frame_prefix(namespace)
    jazzy = distro == "jazzy"
    checker = "goal_checker" if jazzy else "general_goal_checker"
    params: dict[str, dict[str, Any]] = {n: {} for n in node_names(distro, model)}
    params["turtlebot3_node"].update({
        "wheels.separation": m.separation, "wheels.radius": m.radius,
        "enable_stamped_cmd_vel": jazzy, "opencr.id": 200, "opencr.baud_rate": 1000000,
        "opencr.protocol_version": 2.0,
        "namespace": namespace.strip("/"),  # robot.launch.py passes it to the process
    })  # fmt: skip
    params["diff_drive_controller"].update({
        "odometry.publish_tf": True, "odometry.use_imu": True, "odometry.frame_id": "odom",
        "odometry.child_frame_id": "base_footprint", "namespace": namespace.strip("/"),
    })  # fmt: skip
    params["controller_server"].update({
        "FollowPath.max_vel_x": MAX_VEL_X[distro], "FollowPath.min_vel_x": 0.0,
        "FollowPath.max_vel_theta": 1.0, "FollowPath.decel_lim_x": -2.5,
        f"{checker}.xy_goal_tolerance": 0.25, f"{checker}.yaw_goal_tolerance": 0.25,
    })  # fmt: skip
    if "velocity_smoother" in params and jazzy:
        params["velocity_smoother"].update({
            "max_velocity": [0.5, 0.0, 2.5], "min_velocity": [-0.5, 0.0, -2.5],
            "max_accel": [2.5, 0.0, 3.2], "max_decel": [-2.5, 0.0, -3.2],
        })  # fmt: skip
    for costmap in ("global_costmap/global_costmap", "local_costmap/local_costmap"):
        params[costmap].update({"robot_radius": m.robot_radius[distro], "resolution": 0.05})
    params["amcl"].update({
        "base_frame_id": f"{prefix}base_footprint", "odom_frame_id": f"{prefix}odom",
        "global_frame_id": "map", "scan_topic": "scan",
        "robot_model_type": "nav2_amcl::DifferentialMotionModel",
        "update_min_d": 0.25, "update_min_a": 0.2, "transform_tolerance": 0.5 if jazzy else 1.0,
    })  # fmt: skip
    params["bt_navigator"].update({"global_frame": "map", "robot_base_frame": "base_link"})
    params["map_server"]["yaml_filename"] = "warehouse.yaml"  # astiop's map, not ROBOTIS'
    params["robot_state_publisher"].update({
        "robot_description": urdf(model, namespace), "publish_frequency": 20.0,
        "frame_prefix": "", "ignore_timestamp": False,
    })  # fmt: skip
    # robot.launch.py passes frame_id base_scan; under a namespace the description's frame
    # is prefixed, so a working namespaced launch passes that
    params["hlds_laser_publisher"].update(
        {"port": "/dev/ttyUSB0", "frame_id": f"{prefix}base_scan"}
    )
    for manager, managed in lifecycle_nodes(distro):
        params[manager].update({"autostart": True, "node_names": list(managed)})
    return params


def limits(params: dict[str, dict[str, Any]], distro: str) -> Limits:
    controller = params["controller_server"]
    checker = "goal_checker" if distro == "jazzy" else "general_goal_checker"
    tb3 = params["turtlebot3_node"]
    return Limits(
        max_vel_x=float(controller["FollowPath.max_vel_x"]),
        max_vel_theta=float(controller["FollowPath.max_vel_theta"]),
        xy_goal_tolerance=float(controller[f"{checker}.xy_goal_tolerance"]),
        yaw_goal_tolerance=float(controller[f"{checker}.yaw_goal_tolerance"]),
        decel_lim_x=abs(float(controller["FollowPath.decel_lim_x"])),
        robot_radius=float(params["global_costmap/global_costmap"]["robot_radius"]),
        wheel_separation=float(tb3["wheels.separation"]),
        wheel_radius=float(tb3["wheels.radius"]),
    )
