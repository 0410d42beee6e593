"""bt_navigator's /navigate_to_pose on the simulated TurtleBot3, as Nav2 behaves
(ros-navigation/navigation2, jazzy and humble branches):

- nav2_bt_navigator/src/navigators/navigate_to_pose.cpp: feedback each loop — current_pose in
  the global frame, navigation_time since the goal began, distance_remaining along the path from
  the pose closest to the robot, estimated_time_remaining = distance / odometry speed when the
  speed is over 1 cm/s and over 10 cm remain (else 0), number_of_recoveries; /goal_pose is sent
  to its own action server through a client of its own.
- nav2_util/include/nav2_util/simple_action_server.hpp: a new goal preempts the running one,
  which is ABORTED with an empty result; a cancel ends it CANCELED.
- nav2_behavior_tree/.../bt_action_server_impl.hpp: a failure carries the error code of the
  server that failed (jazzy's result has error_code and error_msg; humble's is std_msgs/Empty):
  ComputePathToPose's GOAL_OUTSIDE_MAP=204, GOAL_OCCUPIED=206, NO_VALID_PATH=208 and
  FollowPath's FAILED_TO_MAKE_PROGRESS=105 (nav2_msgs/action/*.action, jazzy).
"""

from __future__ import annotations

import threading
import time
from typing import Any

from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup

from astiop.robot_programs.ros2_common import duration, goal_refusal, now_stamp, stamped
from astiop.robot_programs.turtlebot3 import messages as tm
from astiop.ros2.message_objects import interface_class, to_dict, to_message
from astiop.sim.geometry import path_length
from astiop.sim.simulator import GoalError
from astiop.transports.state import yaw_of

NAVIGATE = "nav2_msgs/action/NavigateToPose"
FEEDBACK_HZ = 10.0
PLAN_HZ = 1.0  # the default tree replans at 1 Hz (RateController)
GOAL_OUTSIDE_MAP, GOAL_OCCUPIED, NO_VALID_PATH = 204, 206, 208
FAILED_TO_MAKE_PROGRESS = 105


class Navigator:
    def __init__(self, robot: Any):
        self.robot = robot
        self.sim = robot.sim
        self.node = robot.nodes["bt_navigator"]
        self.action = interface_class(NAVIGATE)
        self._lock = threading.Lock()
        self._current: Any = None  # the goal handle being executed
        group = ReentrantCallbackGroup()
        self.server = ActionServer(
            self.node,
            self.action,
            "navigate_to_pose",
            execute_callback=self._execute,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _goal: CancelResponse.ACCEPT,
            callback_group=group,
        )
        self._self_client = ActionClient(self.node, self.action, "navigate_to_pose")
        self.node.create_subscription(
            interface_class("geometry_msgs/msg/PoseStamped"), "goal_pose", self._on_goal_pose, 10
        )

    def _on_goal_pose(self, msg: Any) -> None:
        goal = self.action.Goal()
        goal.pose = msg
        self._self_client.send_goal_async(goal)

    def _execute(self, goal_handle: Any) -> Any:
        with self.robot.goal_running():
            return self._run(goal_handle)

    def _run(self, goal_handle: Any) -> Any:
        pose = to_dict(goal_handle.request)["pose"]
        why = goal_refusal(pose, ("", "map"))
        if why:
            return self._end(goal_handle, "abort", 0, why)
        p, q = pose["pose"]["position"], pose["pose"]["orientation"]
        if not self.robot.motors_on:
            return self._end(goal_handle, "abort", FAILED_TO_MAKE_PROGRESS, "motor power is off")
        try:
            goal = self.sim.goto(p["x"], p["y"], yaw_of(q))
        except GoalError as exc:
            return self._end(goal_handle, "abort", _planner_code(str(exc)), str(exc))
        with self._lock:
            self._current = goal_handle
        start, last_plan = time.monotonic(), 0.0
        while self.sim.goal is not None and self.sim.goal.id == goal.id:
            if goal_handle.is_cancel_requested:
                self.sim.cancel("canceled by the action client")
                return self._end(goal_handle, "canceled", 0, "")
            if self.robot.stopping:
                self.sim.cancel("the navigator shut down")
                return self._end(goal_handle, "abort", 0, "the navigator shut down")
            if time.monotonic() - last_plan >= 1.0 / PLAN_HZ:
                self.robot.publish_plan()
                last_plan = time.monotonic()
            self.robot.publish_nav_command()
            goal_handle.publish_feedback(self._feedback(start))
            time.sleep(1.0 / FEEDBACK_HZ)
        self.robot.publish_nav_command(stop=True)  # the controller's zero on completion
        result = self.sim.last_result
        if result is not None and result.id == goal.id and result.status == "succeeded":
            return self._end(goal_handle, "succeed", 0, "")
        if result is not None and result.message.startswith("replaced by a new goal"):
            return self._end(goal_handle, "abort", 0, "")  # preempted: an empty result
        why = result.message if result else "aborted"
        return self._end(goal_handle, "abort", FAILED_TO_MAKE_PROGRESS, why)

    def _feedback(self, start: float) -> Any:
        s = self.sim.snapshot()
        node = self.node
        stamp = now_stamp(node)
        remaining = _path_remaining((s.x, s.y), s.plan)
        speed = abs(s.vx)  # the odometry's linear speed
        eta = remaining / speed if speed > 0.01 and remaining > 0.1 else 0.0
        values = {
            "current_pose": tm.pose_stamped("map", (s.x, s.y, s.theta)),
            "navigation_time": duration(time.monotonic() - start),
            "estimated_time_remaining": duration(eta),
            "number_of_recoveries": 0,
            "distance_remaining": remaining,
        }
        return to_message(self.action.Feedback, stamped(values, stamp))

    def _end(self, goal_handle: Any, how: str, code: int, why: str) -> Any:
        with self._lock:
            if self._current is goal_handle:
                self._current = None
        if why:
            self.node.get_logger().warn(f"navigate_to_pose {how}: {why}")
        getattr(goal_handle, how)()
        fields = self.action.Result.get_fields_and_field_types()
        values = {}
        if "error_code" in fields:  # jazzy and later; humble's result is std_msgs/Empty
            values = {"error_code": code, "error_msg": why}
        return to_message(self.action.Result, values)


def _path_remaining(xy: tuple[float, float], plan) -> float:
    """calculate_path_length from the path pose closest to the robot (navigate_to_pose.cpp)."""
    if not plan:
        return 0.0
    points = list(plan)
    closest = min(
        range(len(points)), key=lambda i: (points[i][0] - xy[0]) ** 2 + (points[i][1] - xy[1]) ** 2
    )
    return float(path_length(points[closest:]))


def _planner_code(why: str) -> int:
    if "outside the map" in why:
        return GOAL_OUTSIDE_MAP
    if "does not fit" in why:
        return GOAL_OCCUPIED
    return NO_VALID_PATH
