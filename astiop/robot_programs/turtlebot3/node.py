"""A TurtleBot3 under Nav2 as real ROS 2 nodes: the warehouse simulator drives a differential
base the TurtleBot3's size, at its speeds, behind turtlebot3_node, diff_drive_controller,
robot_state_publisher, the LDS-01 driver and Nav2's servers, with the names, types, QoS and
parameters in `graph.py` and `params.py`.

The robot starts at START in the map, which is its odometry's origin: /odom reads (0, 0) there,
amcl's /amcl_pose and map → odom give the map pose. amcl is localised from the start, as if the
operator had set the initial pose (set_initial_pose is false upstream). Under a namespace every
name, /tf and /tf_static included, is the namespace's, and the frames carry its prefix
("tb3_1/odom") as turtlebot3_node and the xacro make them. Localisation is exact: /initialpose
is taken and has no effect.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any

from rclpy.parameter import Parameter

from astiop.robot_programs.ros2_common import QOS, RobotNodes, now_stamp, stamped
from astiop.robot_programs.turtlebot3 import messages as tm
from astiop.robot_programs.turtlebot3.graph import (
    CAMERA_TOPIC,
    camera_node,
    endpoints,
    lifecycle_nodes,
    node_names,
)
from astiop.robot_programs.turtlebot3.params import frame_prefix, limits, node_parameters, urdf
from astiop.robot_programs.turtlebot3.services import ServiceHandlers
from astiop.ros2.message_objects import MessageTypeError, interface_class, to_message
from astiop.sim import messages as sm
from astiop.sim.battery import LipoBattery
from astiop.sim.body import Body
from astiop.sim.camera import CameraSpec
from astiop.sim.controller import ControllerGains
from astiop.sim.kinematics import MecanumParams
from astiop.sim.lidar import LidarSpec
from astiop.sim.runner import SimRunner
from astiop.sim.simulator import GoalError, Simulator

START = (4.0, 4.0, 0.0)  # the odometry's origin, in the map
HOLD_S = 1e9  # turtlebot3_node has no /cmd_vel timeout: the OpenCR keeps the last command
# turtlebot3_teleop's BURGER_MAX_LIN_VEL / WAFFLE_MAX_LIN_VEL: the wheels' top speed
MAX_LIN_VEL = {"burger": 0.22, "waffle": 0.26}
MASS_KG = {"burger": 1.0, "waffle": 1.8}
# the Waffle's camera (model.sdf: 1.02974 rad wide, 1920 x 1080 at 30 Hz), drawn smaller and
# slower here: 16:9 at 320 x 180, 5 Hz, only while someone reads it
WAFFLE_CAMERA = CameraSpec(
    width=320, height=180, rate_hz=5.0, fov_deg=math.degrees(1.02974), mount_x=0.07, mount_z=0.12
)


@dataclass(frozen=True)
class Frames:
    map: str
    odom: str
    base_footprint: str
    base_link: str
    base_scan: str
    imu_link: str


def _footprint_box(urdf_xml: str, prefix: str) -> tuple[float, float]:
    """base_link's collision box in the URDF (length, width)."""
    for link in ET.fromstring(urdf_xml).iter("link"):
        if link.get("name") == f"{prefix}base_link":
            size = link.find("collision/geometry/box").get("size").split()
            return float(size[0]), float(size[1])
    raise ValueError("the URDF has no base_link collision box")


class TurtleBot3Nodes(RobotNodes):
    def __init__(self, *, seed: int, speed: float, distro: str, model: str, namespace: str):
        super().__init__()
        self.distro, self.model, self.speed = distro, model, speed
        ns = namespace.strip("/")
        self.namespace = f"/{ns}" if ns else ""
        self.params = node_parameters(distro, model, namespace)
        self.limits = lim = limits(self.params, distro)
        prefix = frame_prefix(namespace)
        self.prefix = prefix
        self.frames = Frames(
            "map",
            *(prefix + f for f in ("odom", "base_footprint", "base_link", "base_scan", "imu_link")),
        )
        self.urdf = urdf(model, namespace)
        length, width = _footprint_box(self.urdf, prefix)
        rpm = MAX_LIN_VEL[model] / (lim.wheel_radius * 2.0 * math.pi / 60.0)
        wheels = MecanumParams(
            lx=0.0, ly=lim.wheel_separation / 2, wheel_radius=lim.wheel_radius, max_wheel_rpm=rpm
        )
        body = Body(
            length,
            width,
            MASS_KG[model],
            wheels,
            differential=True,
            wheel_torque_nm=0.02,
            idle_w=0.3,
        )
        gains = ControllerGains(
            v_max=lim.max_vel_x,
            w_max=lim.max_vel_theta,
            a_max=min(lim.decel_lim_x, 0.5),
            goal_tolerance=lim.xy_goal_tolerance,
            heading_tolerance=lim.yaw_goal_tolerance,
        )
        spec = LidarSpec(
            beams=tm.LDS01_BEAMS,
            range_min=tm.LDS01_RANGE_MIN,
            range_max=tm.LDS01_RANGE_MAX,
            rate_hz=5.0,
        )
        self.camera_node = camera_node(distro, model)
        self.sim = Simulator(
            seed=seed, start=START, body=body, gains=gains, battery=LipoBattery(), lidar_spec=spec,
            camera=WAFFLE_CAMERA if self.camera_node else None,
        )  # fmt: skip
        self.runner = SimRunner(self.sim, speed=speed)
        self.odom_origin = START
        self.motors_on = True
        self.skipped: list[tuple[str, str]] = []  # (name, type) of graph entries not served
        self._pubs: dict[tuple[str, str], Any] = {}
        self._wheel_angles = [0.0, 0.0]
        self._wheel_t = 0.0
        self._amcl_sent: tuple[float, float, float] | None = None
        self.navigator: Any = None

    # -- set-up -----------------------------------------------------------------------------
    def start(self) -> None:
        self.init_context()
        for name in node_names(self.distro, self.model):
            overrides = [Parameter(k, value=v) for k, v in self.params[name].items()]
            self.add_node(
                f"{self.namespace}/{name}",
                key=name,
                parameter_overrides=overrides,
                automatically_declare_parameters_from_overrides=True,
            )
        services = ServiceHandlers(self)
        for ep in endpoints(self.distro, self.model):
            try:
                cls = interface_class(ep.type)
            except MessageTypeError:
                self.skipped.append((ep.name, ep.type))
                continue
            node, name = self.nodes[ep.node], self.namespace + ep.name
            if ep.kind == "pub":
                self._pubs[(ep.node, ep.name)] = node.create_publisher(cls, name, QOS[ep.qos])
            elif ep.kind == "sub":
                callback = self._on_cmd_vel if ep.name == "/cmd_vel" else (lambda _msg: None)
                node.create_subscription(cls, name, callback, QOS[ep.qos])
            elif ep.kind == "srv":
                node.create_service(cls, name, services.handler(ep.name, ep.type))
            elif ep.name != "/navigate_to_pose":  # the one action served here: below
                self.skipped.append((ep.name, "not simulated"))
        from astiop.robot_programs.turtlebot3.navigator import Navigator

        self.navigator = Navigator(self)
        self._timers()
        self._latched()
        self.runner.start()
        self.start_executor()

    def close(self) -> None:
        self.runner.stop()
        self.close_nodes()

    def _timers(self) -> None:
        tb3 = self.nodes["turtlebot3_node"]
        tb3.create_timer(0.05, self._turtlebot3_node)  # publish_timer(50 ms)
        self.nodes["robot_state_publisher"].create_timer(1 / 20.0, self._wheel_tf)
        self.nodes["hlds_laser_publisher"].create_timer(0.2, self._scan)
        self.nodes["amcl"].create_timer(0.2, self._amcl)  # with each scan
        if self.camera_node is not None:
            self.nodes[self.camera_node].create_timer(1 / WAFFLE_CAMERA.rate_hz, self._camera)
        for manager, _managed in lifecycle_nodes(self.distro):  # diagnostic_updater: 1 Hz
            self.nodes[manager].create_timer(1.0, lambda m=manager: self._diagnostics(m))
        for costmap, hz in (
            ("global_costmap/global_costmap", 1.0),
            ("local_costmap/local_costmap", 2.0),
        ):
            self.nodes[costmap].create_timer(1.0 / hz, lambda c=costmap: self._footprint(c))

    def _latched(self) -> None:
        self.send("robot_state_publisher", "/robot_description", {"data": self.urdf})
        self.send("robot_state_publisher", "/tf_static", {"transforms": tm.fixed_joints(self.urdf)})
        grid = sm.occupancy_grid(self.sim.map)  # the warehouse, as the ASTIbot serves it
        self.send("map_server", "/map", grid)
        self.send("global_costmap/global_costmap", "/global_costmap/costmap", grid)

    def send(self, node: str, name: str, message: dict[str, Any], ahead_s: float = 0.0) -> None:
        pub = self._pubs.get((node, name))
        if pub is not None:
            stamp = now_stamp(self.nodes[node])
            if ahead_s:
                ns = stamp["sec"] * 10**9 + stamp["nanosec"] + int(ahead_s * 1e9)
                stamp = {"sec": ns // 10**9, "nanosec": ns % 10**9}
            pub.publish(to_message(pub.msg_type, stamped(message, stamp)))

    # -- the robot ------------------------------------------------------------------------------
    def odom_pose(self, pose=None) -> tuple[float, float, float]:
        return tm.relative(self.odom_origin, pose or self.sim.pose)

    def reset_odometry(self) -> None:
        self.odom_origin = self.sim.pose

    def set_motor_power(self, on: bool) -> None:
        self.motors_on = on
        if not on:  # torque off: the wheels stop and no command moves them
            self.sim.cancel("motor power off")
            self.sim.clear_fault()
            self.sim.set_cmd_vel(0.0, 0.0, 0.0, timeout=HOLD_S)

    def _on_cmd_vel(self, msg: Any) -> None:
        twist = msg.twist if hasattr(msg, "twist") else msg  # TwistStamped on jazzy
        if self.sim.goal is not None or not self.motors_on:
            return  # navigating, Nav2's collision_monitor streams /cmd_vel and its command wins
        self.sim.clear_fault()
        try:
            self.sim.set_cmd_vel(twist.linear.x, 0.0, twist.angular.z, timeout=HOLD_S)
        except GoalError as exc:
            self.nodes["turtlebot3_node"].get_logger().warn(f"/cmd_vel ignored: {exc}")

    def _turtlebot3_node(self) -> None:
        s = self.sim.snapshot()
        r = self.limits.wheel_radius
        left, right = s.wheel_speeds[0], s.wheel_speeds[1]
        dt, self._wheel_t = s.t - self._wheel_t, s.t
        self._wheel_angles = [self._wheel_angles[0] + left * dt, self._wheel_angles[1] + right * dt]
        f = self.frames
        self.send(
            "turtlebot3_node", "/battery_state", tm.battery_state(s.battery_voltage, s.battery_soc)
        )
        self.send("turtlebot3_node", "/imu", tm.imu(f.imu_link, self.odom_pose()[2], s.wz))
        self.send("turtlebot3_node", "/magnetic_field", {"header": tm.header(f.imu_link)})
        joints = tm.joint_states(self.prefix, self._wheel_angles, (left * r, right * r))
        self.send("turtlebot3_node", "/joint_states", joints)
        odom = self.odom_pose((s.x, s.y, s.theta))
        self.send("diff_drive_controller", "/odom", tm.odometry(f, odom, s.vx, s.wz))
        tf = tm.transform(f.odom, f.base_footprint, odom)
        self.send("diff_drive_controller", "/tf", {"transforms": [tf]})

    def _wheel_tf(self) -> None:
        out = []
        for side, angle, y in (
            ("left", self._wheel_angles[0], 1.0),
            ("right", self._wheel_angles[1], -1.0),
        ):
            half = self.limits.wheel_separation / 2 * y
            # the joint's origin rpy (-1.57, 0, 0), then the wheel's turn about its axis
            q = tm.rpy_quaternion(-1.57, 0.0, 0.0)
            c, s_ = math.cos(angle / 2), math.sin(angle / 2)
            rot = {
                "x": q["x"] * c + q["y"] * s_,
                "y": q["y"] * c - q["x"] * s_,
                "z": q["w"] * s_ + q["z"] * c,
                "w": q["w"] * c - q["z"] * s_,
            }
            out.append(
                {
                    "header": tm.header(self.frames.base_link),
                    "child_frame_id": f"{self.prefix}wheel_{side}_link",
                    "transform": {
                        "translation": {"x": 0.0, "y": half, "z": 0.023},
                        "rotation": rot,
                    },
                }
            )
        self.send("robot_state_publisher", "/tf", {"transforms": out})

    def _scan(self) -> None:
        self.send(
            "hlds_laser_publisher",
            "/scan",
            tm.laser_scan(self.frames.base_scan, self.sim.snapshot().scan_ranges),
        )

    def _camera(self) -> None:
        node = self.camera_node
        pub = self._pubs.get((node, CAMERA_TOPIC)) if node is not None else None
        if node is None or pub is None or not pub.get_subscription_count():
            return  # a frame nobody reads is not rendered
        frame = self.sim.camera_image()
        if frame is not None:
            self.send(node, CAMERA_TOPIC, sm.image(*frame, frame=self.prefix + "camera_rgb_frame"))

    def _amcl(self) -> None:
        """map → odom with each scan, stamped transform_tolerance ahead (nav2_amcl's
        sendMapToOdomTransform); /amcl_pose when the filter updates: at the start and after
        update_min_d (m) or update_min_a (rad) of motion."""
        amcl = self.params["amcl"]
        pose = self.sim.pose
        map_odom = {"transforms": [tm.transform("map", self.frames.odom, self.odom_origin)]}
        self.send("amcl", "/tf", map_odom, ahead_s=amcl["transform_tolerance"])
        last = self._amcl_sent
        if last is not None:
            moved = math.hypot(pose[0] - last[0], pose[1] - last[1])
            turned = abs(math.remainder(pose[2] - last[2], 2 * math.pi))
            if moved < amcl["update_min_d"] and turned < amcl["update_min_a"]:
                return
        self.publish_amcl_pose(pose)

    def publish_amcl_pose(self, pose=None) -> None:
        pose = pose or self.sim.pose
        self._amcl_sent = pose
        self.send("amcl", "/amcl_pose", tm.amcl_pose("map", pose))

    def _footprint(self, costmap: str) -> None:
        ns = "/" + costmap.split("/")[0]
        footprint = tm.footprint(self.frames.base_link, self.limits.robot_radius)
        self.send(costmap, f"{ns}/published_footprint", footprint)

    def _diagnostics(self, manager: str) -> None:
        """nav2_lifecycle_manager's CreateDiagnostic: its managed nodes are active."""
        status = {
            "level": b"\x00",  # OK
            "name": f"{manager}: Nav2 Health",
            "message": "Managed nodes are active",
            "hardware_id": "Nav2",
        }
        self.send(manager, "/diagnostics", {"header": tm.header(""), "status": [status]})

    # -- Nav2's command pipeline, while navigating -----------------------------------------------
    def publish_nav_command(self, stop: bool = False) -> None:
        s = self.sim.snapshot()
        v, w = (0.0, 0.0) if stop else (s.vx, s.wz)
        twist = {"linear": {"x": v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": w}}
        msg = (
            {"header": tm.header(self.frames.base_link), "twist": twist}
            if self.distro == "jazzy"
            else twist
        )
        for node, name in (
            ("controller_server", "/cmd_vel_nav"),
            ("velocity_smoother", "/cmd_vel_smoothed" if self.distro == "jazzy" else "/cmd_vel"),
            ("collision_monitor", "/cmd_vel"),
        ):
            if (node, name) in self._pubs:
                self.send(node, name, msg)

    def publish_plan(self) -> None:
        plan = self.sim.plan
        if plan:
            self.send("planner_server", "/plan", tm.path("map", plan))
