"""The simulated ASTIbot as real ROS 2 nodes (rclpy over DDS): the catalog's nodes, every topic
at its rate with the QoS a real driver uses, every service, NavigateToPose as an action server,
the parameters, and `/cmd_vel` obeyed with a lapse.

rclpy API used here is Humble's too (rclpy's humble branch: node.py, action/server.py,
executors.py, qos.py).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup

from astiop.robot.safety import clamp_twist
from astiop.robot_programs.ros2_common import (
    MAP_TYPE,
    QOS,
    QUIET_EVENTS,
    RELIABLE,
    RobotNodes,
    duration,
    goal_refusal,
    stamped,
)
from astiop.ros2.catalog import CAMERA_TOPICS
from astiop.ros2.message_objects import interface_class, to_dict, to_message
from astiop.sim import messages as sm
from astiop.sim.simulator import GoalError, Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.state import yaw_of

LAPSE_S = 0.5  # the base stops when /cmd_vel stops for this long (wall time)
FEEDBACK_HZ = 5.0
ABORTED = 9000  # nav2_msgs' UNKNOWN error code (kilted names it; jazzy has the field)
__all__ = ["QOS", "SimRobotNodes"]  # tests read QOS from here


class SimRobotNodes(RobotNodes):
    """The simulator at real time behind the catalog's ROS 2 nodes, in one rclpy context.

    One robot of a fleet (`fleet.py`) is given its `sim` (stepped by the fleet) and serves
    every name under its `namespace` (/astibot_1/cmd_vel, node /astibot_1/astibot_base), in
    its `parent`'s context or on a domain of its own."""

    def __init__(
        self,
        *,
        seed: int,
        speed: float,
        locations_db: Path,
        sim: Simulator | None = None,
        namespace: str = "",
        parent: RobotNodes | None = None,
        domain_id: int | None = None,
    ):
        super().__init__(parent, domain_id)
        self.sim = sim or Simulator(seed=seed)
        self.ns = namespace
        self.speed = speed  # sim seconds per wall second
        self.store = Store(locations_db)  # the robot's own named locations
        self.backend = SimBackend(
            self.sim, self.store, realtime=True, speed=speed, stepped_elsewhere=sim is not None
        )
        self.catalog = self.backend.catalog  # the ASTIbot's, its camera's if the sim has one
        self.limits = {
            "max_linear_speed": self.catalog.params[("/astibot_base", "max_linear_speed")].value,
            "max_angular_speed": self.catalog.params[("/astibot_base", "max_angular_speed")].value,
        }
        self._publishers: dict[str, Any] = {}

    # -- set-up -----------------------------------------------------------------------------
    def start(self) -> None:
        self.init_context()
        for name in self.catalog.nodes:
            if name == "/astiop_agent":
                continue  # astiop's own node: the locations services live on the navigator here
            self.add_node(self.ns + name, key=name)
        for spec in self.catalog.topics.values():
            if spec.publisher:
                self._publish(spec.name, spec.type, spec.publisher, spec.rate_hz, spec.qos)
        self._publish("/map", MAP_TYPE, "/navigator", 0, "transient_local")
        base = self.nodes["/astibot_base"]
        base.create_subscription(
            interface_class("geometry_msgs/msg/Twist"),
            self.ns + "/cmd_vel",
            self._on_cmd_vel,
            RELIABLE,
        )
        for spec in self.catalog.services.values():
            node = self.nodes.get(spec.node) or self.nodes["/navigator"]
            node.create_service(
                interface_class(spec.type), self.ns + spec.name, self._service_handler(spec.name)
            )
        nav = self.catalog.actions["/navigate_to_pose"]
        self._action = ActionServer(
            self.nodes[nav.node],
            interface_class(nav.type),
            self.ns + nav.name,
            execute_callback=self._navigate,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _goal: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup(),
        )
        self._declare_parameters()
        self.backend.start()
        self.start_executor()

    def close(self) -> None:
        self.backend.close()
        self.close_nodes()
        self.store.close()

    # -- topics -----------------------------------------------------------------------------
    def _publish(self, name: str, type_: str, node: str, rate_hz: float, qos: str) -> None:
        cls = interface_class(type_)
        pub = self.nodes[node].create_publisher(
            cls, self.ns + name, QOS[qos], event_callbacks=QUIET_EVENTS
        )
        self._publishers[name] = pub

        def send() -> None:
            if name in CAMERA_TOPICS and not pub.get_subscription_count():
                return  # a frame nobody reads is not rendered (a fleet's robots, each 5 Hz)
            message = self._message(name)
            if message is not None:
                now = self.nodes[node].get_clock().now().to_msg()
                stamp = {"sec": now.sec, "nanosec": now.nanosec}
                pub.publish(to_message(cls, stamped(message, stamp)))

        if rate_hz > 0:
            self.every(1.0 / rate_hz, send)
        else:
            send()  # latched: published once, kept for late subscribers

    def _message(self, name: str) -> dict[str, Any] | None:
        if name == "/map":
            return sm.occupancy_grid(self.sim.map)
        if name == "/plan" and self.sim.goal is None:
            return None  # a path only while navigating
        return self.backend.message(name)

    def _on_cmd_vel(self, msg: Any) -> None:
        twist, _notes = clamp_twist(
            to_dict(msg), self.limits["max_linear_speed"], self.limits["max_angular_speed"]
        )
        try:
            self.sim.set_cmd_vel(
                twist["linear"]["x"],
                twist["linear"]["y"],
                twist["angular"]["z"],
                timeout=LAPSE_S * self.speed,  # the sim's clock runs `speed` times the wall's
            )
        except GoalError as exc:  # e-stopped or faulted: the base does not move
            self.nodes["/astibot_base"].get_logger().warn(
                f"/cmd_vel ignored: {exc}", throttle_duration_sec=5.0
            )

    # -- services ---------------------------------------------------------------------------
    def _service_handler(self, name: str):
        def handle(request: Any, response: Any) -> Any:
            return to_message(type(response), self.backend.serve(name, to_dict(request)))

        return handle

    # -- the action ---------------------------------------------------------------------------
    def _navigate(self, goal_handle: Any) -> Any:
        with self.goal_running():
            return self._navigate_goal(goal_handle)

    def _navigate_goal(self, goal_handle: Any) -> Any:
        action = interface_class(self.catalog.actions["/navigate_to_pose"].type)
        request = to_dict(goal_handle.request)
        pose = request["pose"]
        why = goal_refusal(pose)
        if why:
            return _ended(goal_handle, action, "abort", why)
        p, q = pose["pose"]["position"], pose["pose"]["orientation"]
        try:
            goal = self.sim.goto(p["x"], p["y"], yaw_of(q))
        except GoalError as exc:
            return _ended(goal_handle, action, "abort", str(exc))
        start = time.monotonic()
        clock = self.nodes["/navigator"].get_clock()
        while self.sim.goal is not None and self.sim.goal.id == goal.id:
            if goal_handle.is_cancel_requested:
                self.sim.cancel("canceled by the action client")
                return _ended(goal_handle, action, "canceled", "")
            if self.stopping:
                self.sim.cancel("the robot's navigator shut down")
                return _ended(goal_handle, action, "abort", "the navigator shut down")
            goal_handle.publish_feedback(self._feedback(action, start, clock))
            time.sleep(1.0 / FEEDBACK_HZ)
        result = self.sim.last_result
        if result is not None and result.id == goal.id and result.status == "succeeded":
            return _ended(goal_handle, action, "succeed", "")
        return _ended(goal_handle, action, "abort", result.message if result else "aborted")

    def _feedback(self, action: Any, start: float, clock: Any) -> Any:
        s = self.sim.snapshot()
        elapsed = time.monotonic() - start
        now = clock.now().to_msg()
        wall_speed = self.sim.speed() * self.speed
        # as nav2's bt_navigator estimates it: 0 when (nearly) still or (nearly) there
        slow = wall_speed < 0.01 or s.distance_remaining < 0.1
        remaining = 0.0 if slow else s.distance_remaining / wall_speed
        return to_message(
            action.Feedback,
            {
                "current_pose": {
                    "header": {
                        "stamp": {"sec": now.sec, "nanosec": now.nanosec},
                        "frame_id": "map",
                    },
                    "pose": {
                        "position": {"x": s.x, "y": s.y, "z": 0.0},
                        "orientation": sm.quaternion(s.theta),
                    },
                },
                "navigation_time": duration(elapsed),
                "estimated_time_remaining": duration(remaining),
                "number_of_recoveries": 0,
                "distance_remaining": s.distance_remaining,
            },
        )

    # -- parameters ---------------------------------------------------------------------------
    def _declare_parameters(self) -> None:
        for (node_name, name), spec in self.catalog.params.items():
            node = self.nodes.get(node_name)
            if node is None:
                continue
            descriptor = ParameterDescriptor(
                description=spec.description, read_only=not spec.writable
            )
            if spec.writable and spec.minimum is not None and spec.maximum is not None:
                descriptor.floating_point_range = [
                    FloatingPointRange(from_value=spec.minimum, to_value=spec.maximum, step=0.0)
                ]
            node.declare_parameter(name, spec.value, descriptor)
        self.nodes["/astibot_base"].add_on_set_parameters_callback(self._on_set_parameters)

    def _on_set_parameters(self, params: list[Any]) -> SetParametersResult:
        # rclpy has already refused a wrong type, a read-only parameter and an out-of-range value
        for param in params:
            if param.name in self.limits:
                self.limits[param.name] = float(param.value)
                if param.name == "max_linear_speed":  # goals drive no faster either
                    with self.sim.lock:
                        self.sim.gains = replace(self.sim.gains, v_max=float(param.value))
        return SetParametersResult(successful=True)


def _ended(goal_handle: Any, action: Any, how: str, why: str) -> Any:
    getattr(goal_handle, how)()
    fields = action.Result.get_fields_and_field_types()
    values = {}
    if "error_code" in fields:  # Jazzy and later; Humble's result is std_msgs/Empty
        values = {"error_code": ABORTED if how == "abort" else 0, "error_msg": why}
    return to_message(action.Result, values)
