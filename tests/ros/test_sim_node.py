"""`astiop sim node` on real ROS 2 (rclpy, Fast DDS, loopback only): read and driven as a robot by a
test's own rclpy node in another process."""

from __future__ import annotations

import math
import time

import pytest

from astiop.ros2.catalog import astibot_catalog
from tests.ros import require_ros, ros_client, sim_node, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]

CATALOG = astibot_catalog()
SHIPPING = (37.6, 4.0)
ZONE_A = (15.0, 3.5)


@pytest.fixture  # one robot per test: two on a worker's domain would answer both
def robot():
    require_ros()
    with sim_node(speed=4.0) as node:
        yield node


@pytest.fixture
def client():
    require_ros()
    with ros_client() as c:
        yield c


def _types():
    from astiop.ros2.message_objects import interface_class

    return interface_class


def _goal(x: float, y: float, qz: float = 0.0, qw: float = 1.0):
    from nav2_msgs.action import NavigateToPose

    goal = NavigateToPose.Goal()
    goal.pose.header.frame_id = "map"
    goal.pose.pose.position.x, goal.pose.pose.position.y = x, y
    goal.pose.pose.orientation.z, goal.pose.pose.orientation.w = qz, qw
    return goal


def _undocked(client) -> list:
    """Undock and wait until the robot is idle; the /odom messages from then on."""
    from astiop_msgs.msg import RobotStatus
    from nav_msgs.msg import Odometry
    from std_srvs.srv import Trigger

    status = client.collect(RobotStatus, "/robot_status")
    answer = client.call(Trigger, "/undock", Trigger.Request(), resend_s=5.0)
    # sent again, the first may have undocked it: the second is then told so
    assert answer.success or "not docked" in answer.message, answer
    assert until(lambda: status and status[-1][1].state == "idle" and not status[-1][1].docked, 30)
    odom = client.collect(Odometry, "/odom")
    assert until(lambda: odom, 10), "no /odom"
    return odom


def test_every_catalog_topic_arrives_with_its_type_at_its_rate(robot, client):
    from astiop.robot_programs.ros2_node.node import QOS

    cls = _types()
    published = [t for t in CATALOG.topics.values() if t.publisher]
    graph = until(lambda: dict(client.node.get_topic_names_and_types()), 10)
    until(
        lambda: (
            all(t.name in graph for t in published)
            or graph.update(dict(client.node.get_topic_names_and_types()))
        ),
        10,
    )
    for spec in published:
        assert graph.get(spec.name) == [spec.type], spec.name
    got = {t.name: client.collect(cls(t.type), t.name, QOS[t.qos]) for t in published}
    got["/map"] = client.collect(cls("nav_msgs/msg/OccupancyGrid"), "/map", QOS["transient_local"])
    until(lambda: all(got[n] for n in ("/odom", "/scan", "/battery_status", "/tf")), 10)
    window = 3.0
    start = time.monotonic()
    time.sleep(window)
    for spec in published:
        if spec.rate_hz == 0 or spec.name == "/plan":
            continue
        n = sum(1 for t, _ in got[spec.name] if start <= t < start + window)
        assert 0.5 * spec.rate_hz * window <= n <= 1.3 * spec.rate_hz * window + 1, (
            f"{spec.name}: {n} messages in {window} s at {spec.rate_hz} Hz"
        )
    assert got["/tf_static"] and got["/map"], "latched topics reach a late subscriber"
    assert got["/plan"] == [], "no path while the robot has no goal"
    stamp = got["/battery_status"][-1][1].header.stamp
    assert abs(stamp.sec + stamp.nanosec * 1e-9 - time.time()) < 5.0, "stamped with the clock"
    scan = got["/scan"][-1][1]
    assert len(scan.ranges) == 360 and scan.header.frame_id == "laser"


def test_services_answer_as_the_catalog_says(robot, client):
    from astiop_msgs.srv import ListLocations
    from std_srvs.srv import Trigger

    listed = client.call(ListLocations, "/list_locations", ListLocations.Request())
    assert "shipping" in listed.names and len(listed.poses) == len(listed.names)
    load = client.call(Trigger, "/conveyor/load", Trigger.Request())
    assert load.success is False and load.message, "a load only at a station, said why"


def test_goto_position_arrives_and_stop_cancels(client):
    from astiop_msgs.srv import GotoPosition
    from geometry_msgs.msg import Pose2D
    from std_srvs.srv import Trigger

    with sim_node(speed=8.0):
        poses = client.collect(Pose2D, "/robot_pose")
        r = client.call(GotoPosition, "/goto_position", GotoPosition.Request(name="shipping"))
        assert r.success and "navigating to shipping" in r.message, r.message

        def near(xy, tol=0.3):
            return poses and math.hypot(poses[-1][1].x - xy[0], poses[-1][1].y - xy[1]) < tol

        assert until(lambda: near(SHIPPING), 90), (
            f"not at shipping: {poses[-1][1] if poses else None}"
        )
        r = client.call(GotoPosition, "/goto_position", GotoPosition.Request(x=25.0, y=21.0))
        assert r.success, r.message
        time.sleep(1.0)
        stop = client.call(Trigger, "/stop", Trigger.Request())
        assert stop.success and "goal canceled" in stop.message
        time.sleep(0.5)
        held = poses[-1][1]
        time.sleep(1.0)
        assert math.hypot(poses[-1][1].x - held.x, poses[-1][1].y - held.y) < 0.02


def test_navigate_to_pose_feedback_arrival_cancel_and_refusals(client):
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient
    from std_srvs.srv import Trigger

    with sim_node(speed=8.0):
        action = ActionClient(client.node, NavigateToPose, "/navigate_to_pose")
        assert action.wait_for_server(timeout_sec=15)

        def send(goal):
            feedback: list = []
            handle = client.result(action.send_goal_async(goal, feedback_callback=feedback.append))
            assert handle.accepted
            return handle, feedback

        handle, feedback = send(_goal(*ZONE_A))
        done = client.result(handle.get_result_async(), 90)
        assert done.status == GoalStatus.STATUS_SUCCEEDED, done.result.error_msg
        remaining = [f.feedback.distance_remaining for f in feedback]
        assert len(remaining) >= 2 and remaining[0] > remaining[-1] >= 0.0

        handle, _ = send(_goal(*SHIPPING))
        time.sleep(1.0)
        client.result(handle.cancel_goal_async())
        assert client.result(handle.get_result_async()).status == GoalStatus.STATUS_CANCELED

        handle, _ = send(_goal(*SHIPPING))
        time.sleep(1.0)
        assert client.call(Trigger, "/stop", Trigger.Request()).success
        ended = client.result(handle.get_result_async())
        assert ended.status == GoalStatus.STATUS_ABORTED and "stop" in ended.result.error_msg
        handle, _ = send(_goal(*SHIPPING))  # the stop holds: no goal until /release
        ended = client.result(handle.get_result_async())
        assert ended.status == GoalStatus.STATUS_ABORTED and "latched" in ended.result.error_msg
        assert client.call(Trigger, "/release", Trigger.Request()).success

        for goal, why in (
            (_goal(15.0, 3.5, qz=1e308, qw=1e308), "unit quaternion"),
            (_goal(80.0, 3.5), "outside"),
        ):
            handle, _ = send(goal)
            ended = client.result(handle.get_result_async())
            assert ended.status == GoalStatus.STATUS_ABORTED and why in ended.result.error_msg


def test_parameters_are_typed_ranged_and_take_effect(client):
    from geometry_msgs.msg import Twist
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters

    def set_param(node: str, name: str, value: ParameterValue):
        req = SetParameters.Request(parameters=[Parameter(name=name, value=value)])
        return client.call(SetParameters, f"{node}/set_parameters", req).results[0]

    with sim_node(speed=1.0):
        got = client.call(
            GetParameters,
            "/astibot_base/get_parameters",
            GetParameters.Request(names=["max_linear_speed"]),
        )
        value = got.values[0]
        assert value.type == ParameterType.PARAMETER_DOUBLE and value.double_value == 0.8
        wrong = set_param(
            "/astibot_base",
            "max_linear_speed",
            ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=1),
        )
        assert not wrong.successful and "type" in wrong.reason.lower()
        double = ParameterType.PARAMETER_DOUBLE
        too_fast = set_param(
            "/astibot_base", "max_linear_speed", ParameterValue(type=double, double_value=9.0)
        )
        assert not too_fast.successful
        read_only = set_param(
            "/lidar_driver", "frequency", ParameterValue(type=double, double_value=20.0)
        )
        assert not read_only.successful
        slow = set_param(
            "/astibot_base", "max_linear_speed", ParameterValue(type=double, double_value=0.3)
        )
        assert slow.successful, slow.reason

        # the clamp follows the parameter: 1 m/s asked, 0.3 m/s driven
        odom = _undocked(client)
        pub = client.node.create_publisher(Twist, "/cmd_vel", 10)
        twist = Twist()
        twist.linear.y = 1.0
        for _ in range(20):
            pub.publish(twist)
            time.sleep(0.1)
        speeds = [math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y) for _, m in odom[-20:]]
        assert 0.1 < max(speeds) <= 0.3 + 1e-3, speeds


def test_cmd_vel_moves_the_base_and_the_lapse_stops_it(client):
    from geometry_msgs.msg import Twist

    with sim_node(speed=2.0):
        odom = _undocked(client)
        start = odom[-1][1].pose.pose.position
        pub = client.node.create_publisher(Twist, "/cmd_vel", 10)
        twist = Twist()
        twist.linear.x = 0.4
        for _ in range(15):
            pub.publish(twist)
            time.sleep(0.1)
        moved = odom[-1][1].pose.pose.position
        assert math.hypot(moved.x - start.x, moved.y - start.y) > 0.2
        time.sleep(1.5)  # no more commands: the 0.5 s lapse has stopped the base
        last = odom[-1][1].twist.twist
        assert math.hypot(last.linear.x, last.linear.y) < 1e-3


def test_stop_latches_the_base_until_release(client):
    """As a safety controller holds it: after /stop, /cmd_vel is ignored and goals refused
    (read from the robot's own /odom and /robot_status) until /release."""
    from astiop_msgs.msg import RobotStatus
    from astiop_msgs.srv import GotoPosition
    from geometry_msgs.msg import Twist
    from std_srvs.srv import Trigger

    with sim_node(speed=2.0):
        graph = lambda: dict(client.node.get_service_names_and_types())  # noqa: E731
        assert until(lambda: graph().get("/release"), 15) == ["std_srvs/srv/Trigger"]
        odom = _undocked(client)
        status = client.collect(RobotStatus, "/robot_status")
        pub = client.node.create_publisher(Twist, "/cmd_vel", 10)
        twist = Twist()
        twist.linear.x = -0.4  # it faces west after undocking: backwards is +x

        def back_up() -> list:
            first = len(odom)
            for _ in range(15):
                pub.publish(twist)
                time.sleep(0.1)
            return [m for _, m in odom[first:]]

        assert client.call(Trigger, "/stop", Trigger.Request()).success
        rest = odom[-1][1].pose.pose.position
        during = back_up()
        assert during and max(abs(m.twist.twist.linear.x) for m in during) < 1e-3
        held = odom[-1][1].pose.pose.position
        assert math.hypot(held.x - rest.x, held.y - rest.y) < 1e-3
        goal = client.call(GotoPosition, "/goto_position", GotoPosition.Request(name="shipping"))
        assert not goal.success and "latched" in goal.message, goal.message
        assert until(lambda: status and status[-1][1].state == "e_stopped", 5)
        released = client.call(Trigger, "/release", Trigger.Request())
        assert released.success, released.message
        during = back_up()
        assert max(abs(m.twist.twist.linear.x) for m in during) > 0.2
        moved = odom[-1][1].pose.pose.position
        assert moved.x > rest.x + 0.2


def test_a_killed_node_leaves_nothing_behind_for_the_next(monkeypatch):
    require_ros()
    import os

    from sensor_msgs.msg import BatteryState

    from tests.ros import SimNode

    # a SIGKILLed participant's endpoints stay in every peer's discovery data until its lease
    # runs out (Fast DDS: 20 s): on the worker's own domain, the next test would find a /stop
    # nobody serves. This test's robots and client keep to a domain of their own.
    monkeypatch.setenv("ROS_DOMAIN_ID", str((int(os.environ["ROS_DOMAIN_ID"]) + 50) % 102))

    first = SimNode()
    first.wait_ready()
    first.kill()  # SIGKILL: no clean shutdown
    with sim_node(), ros_client("after_kill") as client:
        battery = client.collect(BatteryState, "/battery_status")
        assert until(lambda: battery, 15), "the new robot publishes"

        def names():
            return [n for n in client.node.get_node_names() if n != "after_kill"]

        until(lambda: "astibot_base" in names(), 10)
        time.sleep(1.0)
        listed = names()
        assert sorted(listed) == sorted(set(listed)) and "astibot_base" in listed, listed


def test_a_goal_running_when_the_node_stops_is_aborted_and_the_client_told(client):
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient

    from tests.ros import SimNode

    node = SimNode(speed=2.0)
    node.wait_ready()
    try:
        action = ActionClient(client.node, NavigateToPose, "/navigate_to_pose")
        assert action.wait_for_server(timeout_sec=15)
        handle = client.result(action.send_goal_async(_goal(*SHIPPING)))
        assert handle.accepted
        result = handle.get_result_async()  # asked at once, as ros2cli's send_goal asks
        time.sleep(1.0)
        assert node.stop() == 0  # SIGTERM mid-goal: still a clean exit
        ended = client.result(result, 10)
        assert ended.status == GoalStatus.STATUS_ABORTED and "shut down" in ended.result.error_msg
        assert not any("Traceback" in line for line in node.lines), "\n".join(node.lines)
    finally:
        node.kill()
