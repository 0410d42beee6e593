"""`astiop sim node --robot turtlebot3` on real ROS 2 (rclpy, loopback only): a TurtleBot3 under
Nav2 with upstream's names and types (the table in astiop/robot_programs/turtlebot3/graph.py, read
from ROBOTIS-GIT/turtlebot3 and ros-navigation/navigation2), read and driven by a test's own
rclpy node in another process."""

from __future__ import annotations

import math
import subprocess
import sys
import time

import pytest

from astiop.robot_programs.turtlebot3.graph import endpoints
from tests.ros import require_ros, ros_client, tb3_node, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]

START = (4.0, 4.0)  # the TurtleBot3's start in the map: its odometry's origin
RCLPY_SERVICES = (
    "describe_parameters", "get_parameter_types", "get_parameters", "list_parameters",
    "set_parameters", "set_parameters_atomically", "get_type_description",
)  # fmt: skip
ASTIBOT_ONLY = ("/stop", "/dock", "/undock", "/robot_pose", "/robot_status", "/goto_position")


@pytest.fixture(scope="module")
def tb3():
    require_ros()
    with tb3_node(speed=8.0) as node:
        yield node


@pytest.fixture
def client():
    require_ros()
    with ros_client("tb3_probe") as c:
        yield c


def _importable(type_name: str) -> bool:
    from astiop.ros2.message_objects import MessageTypeError, interface_class

    try:
        interface_class(type_name)
    except MessageTypeError:
        return False
    return True


def _split(full: str) -> tuple[str, str]:
    ns, _, base = full.rpartition("/")
    return base, ns or "/"


def _graph_differences(client, distro: str, ns: str, model: str = "burger") -> list[str]:
    """Where each of the robot's nodes differs from the upstream table: a node missing, or a
    topic, service or action it lacks or has beyond the table (rclpy's own names aside). Other
    participants on the domain (a test's client, one just gone) are not the robot's."""
    from rclpy.action import get_action_server_names_and_types_by_node

    from astiop.robot_programs.turtlebot3.graph import endpoints, node_names

    node = client.node
    live = {(ns_.rstrip("/") + "/" + n) for n, ns_ in node.get_node_names_and_namespaces()}
    wrong = [f"node {ns}/{n} missing" for n in node_names(distro, model) if f"{ns}/{n}" not in live]
    if wrong:
        return wrong
    readers = {
        "pub": node.get_publisher_names_and_types_by_node,
        "sub": node.get_subscriber_names_and_types_by_node,
        "srv": node.get_service_names_and_types_by_node,
    }
    table = endpoints(distro, model)
    for name in node_names(distro, model):
        base, node_ns = _split(f"{ns}/{name}")
        for kind, read in readers.items():
            want = {
                (ns + ep.name, ep.type)
                for ep in table
                if ep.node == name and ep.kind == kind and _importable(ep.type)
            }
            got = {(n, t) for n, types in read(base, node_ns) for t in types}
            got = {(n, t) for n, t in got if not _rclpys_own(n)}
            wrong += [f"{name} lacks {kind} {n} {t}" for n, t in sorted(want - got)]
            wrong += [f"{name} has {kind} {n} {t}, not upstream's" for n, t in sorted(got - want)]
        want = {
            (ns + ep.name, ep.type)
            for ep in table
            if ep.node == name and ep.kind == "action" and ep.name == "/navigate_to_pose"
        }
        got = {
            (n, t)
            for n, types in get_action_server_names_and_types_by_node(node, base, node_ns)
            for t in types
        }
        if got != want:
            wrong.append(f"{name} serves actions {sorted(got)}, not {sorted(want)}")
    return wrong


def _rclpys_own(name: str) -> bool:
    """rclpy's names on every node (logging, parameters, the action's internals) and rcl's time
    source (/clock, on nodes the files give use_sim_time: true)."""
    return (
        name in ("/rosout", "/parameter_events", "/clock")
        or "/_action/" in name
        or name.rsplit("/", 1)[-1] in RCLPY_SERVICES
    )


def _graph_matches(client, distro: str = "jazzy", ns: str = "", model: str = "burger") -> None:
    wrong = until(lambda: not _graph_differences(client, distro, ns, model), 20, step=0.5)
    assert wrong, "\n".join(_graph_differences(client, distro, ns, model))


def _param(client, node: str, name: str):
    from rcl_interfaces.srv import GetParameters
    from rclpy.parameter import parameter_value_to_python

    reply = client.call(
        GetParameters, f"{node}/get_parameters", GetParameters.Request(names=[name])
    )
    return parameter_value_to_python(reply.values[0])


def _latest(client, msg_type, topic: str, qos=10, timeout: float = 10.0):
    got = client.collect(msg_type, topic, qos)
    assert until(lambda: got, timeout), f"nothing on {topic}"
    return got


def _xy(msg) -> tuple[float, float]:
    p = msg.pose.pose.position
    return p.x, p.y


def _amcl(client, ns: str = ""):
    from geometry_msgs.msg import PoseWithCovarianceStamped

    from astiop.robot_programs.ros2_common import LATCHED

    return _latest(client, PoseWithCovarianceStamped, f"{ns}/amcl_pose", LATCHED)


def _goal(x: float, y: float):
    from nav2_msgs.action import NavigateToPose

    goal = NavigateToPose.Goal()
    goal.pose.header.frame_id = "map"
    goal.pose.pose.position.x, goal.pose.pose.position.y = x, y
    goal.pose.pose.orientation.w = 1.0
    return goal


def _send(client, x: float, y: float, feedback: list | None = None, ns: str = ""):
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient

    action = ActionClient(client.node, NavigateToPose, f"{ns}/navigate_to_pose")
    assert action.wait_for_server(timeout_sec=10)
    callback = (lambda m: feedback.append(m.feedback)) if feedback is not None else None
    handle = client.result(action.send_goal_async(_goal(x, y), feedback_callback=callback))
    assert handle.accepted
    return handle


def test_the_graph_is_upstreams_on_jazzy_with_no_astibot_name(tb3, client):
    _graph_matches(client)  # and so none of the ASTIbot's names (ASTIBOT_ONLY) is on it
    assert not [n for n in ASTIBOT_ONLY if n in {ep.name for ep in endpoints("jazzy")}]
    topics = dict(client.node.get_topic_names_and_types())
    assert topics["/cmd_vel"] == ["geometry_msgs/msg/TwistStamped"]  # enable_stamped_cmd_vel
    # parameters from turtlebot3_navigation2/param/burger.yaml and turtlebot3_bringup's (jazzy)
    assert _param(client, "/controller_server", "FollowPath.max_vel_x") == 0.3
    assert _param(client, "/velocity_smoother", "max_velocity") == [0.5, 0.0, 2.5]
    assert _param(client, "/global_costmap/global_costmap", "robot_radius") == 0.1
    assert _param(client, "/amcl", "base_frame_id") == "base_footprint"
    assert _param(client, "/turtlebot3_node", "wheels.separation") == 0.16
    assert _param(client, "/turtlebot3_node", "enable_stamped_cmd_vel") is True


def test_battery_state_is_filled_as_turtlebot3_node_fills_it(tb3, client):
    from sensor_msgs.msg import BatteryState

    battery = _latest(client, BatteryState, "/battery_state")[-1][1]
    assert 1.0 < battery.percentage <= 100.0  # 0-100, not the message's 0-1
    assert 9.9 <= battery.voltage <= 12.6 and battery.present  # a 3S pack, in volts
    assert battery.design_capacity == pytest.approx(1.8)
    assert battery.current == 0.0  # turtlebot3_node leaves it unset


def test_scan_is_the_lds01s_and_no_return_is_zero(tb3, client):
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import LaserScan

    scan = _latest(client, LaserScan, "/scan", qos_profile_sensor_data)[-1][1]
    assert (len(scan.ranges), scan.angle_min) == (360, 0.0)
    assert (scan.range_min, scan.range_max) == (pytest.approx(0.12), pytest.approx(3.5))
    assert scan.header.frame_id == "base_scan"
    returns = [r for r in scan.ranges if r != 0.0]
    assert all(0.12 <= r <= 3.5 for r in returns)
    assert len(returns) < 360  # the warehouse is bigger than 3.5 m: no-return beams are 0.0


def test_cmd_vel_drives_odom_from_its_origin_while_amcl_gives_the_map_pose(tb3, client):
    from geometry_msgs.msg import TwistStamped
    from nav_msgs.msg import Odometry

    start_map = _xy(_amcl(client)[-1][1])
    odom = _latest(client, Odometry, "/odom")
    start_odom = _xy(odom[-1][1])
    assert math.dist(start_map, start_odom) > 3.0  # odometry began at (0, 0), not at (4, 4)
    pub = client.node.create_publisher(TwistStamped, "/cmd_vel", 10)
    cmd = TwistStamped()
    cmd.twist.linear.x = 0.2
    assert until(
        lambda: (pub.publish(cmd), odom[-1][1].pose.pose.position.x - start_odom[0] > 0.4)[1], 15
    )
    cmd.twist.linear.x = 0.0
    pub.publish(cmd)
    assert until(lambda: (pub.publish(cmd), abs(odom[-1][1].twist.twist.linear.x) < 1e-3)[1], 10)
    assert odom[-1][1].header.frame_id == "odom" and odom[-1][1].child_frame_id == "base_footprint"
    end_odom = _xy(odom[-1][1])
    amcl = _amcl(client)
    end_map = _xy(amcl[-1][1])
    assert amcl[-1][1].header.frame_id == "map"
    # map pose = odometry + where the odometry began, not the odometry itself
    moved = (end_odom[0] - start_odom[0], end_odom[1] - start_odom[1])
    assert math.dist(end_map, (start_map[0] + moved[0], start_map[1] + moved[1])) < 0.3
    assert math.dist(end_map, end_odom) > 3.0


def test_motor_power_off_holds_the_base_and_reset_odometry_moves_only_odom(tb3, client):
    from geometry_msgs.msg import TwistStamped
    from nav_msgs.msg import Odometry
    from std_srvs.srv import SetBool, Trigger

    assert client.call(SetBool, "/motor_power", SetBool.Request(data=False)).success
    odom = _latest(client, Odometry, "/odom")
    before = _xy(odom[-1][1])
    pub = client.node.create_publisher(TwistStamped, "/cmd_vel", 10)
    cmd = TwistStamped()
    cmd.twist.linear.x = 0.2
    for _ in range(10):  # torque off: no command moves it
        pub.publish(cmd)
        time.sleep(0.05)
    time.sleep(0.3)
    assert math.dist(_xy(odom[-1][1]), before) < 0.01
    # the OpenCR keeps the last command: a zero one last (in order after the others, however
    # late they arrive), so nothing drives on once the torque is back
    for _ in range(3):
        pub.publish(TwistStamped())
        time.sleep(0.05)
    assert client.call(SetBool, "/motor_power", SetBool.Request(data=True)).success
    map_before = _xy(_amcl(client)[-1][1])
    reply = client.call(Trigger, "/reset_odometry", Trigger.Request())
    assert reply.success and reply.message == "Odometry reset"
    assert until(lambda: math.dist(_xy(odom[-1][1]), (0.0, 0.0)) < 0.01, 5)
    assert math.dist(_xy(_amcl(client)[-1][1]), map_before) < 0.01  # the map pose stays


def test_navigate_to_pose_gives_feedback_then_succeeds_near_the_target(tb3, client):
    from action_msgs.msg import GoalStatus
    from nav_msgs.msg import Path
    from std_srvs.srv import Empty

    x, y = _xy(_amcl(client)[-1][1])
    target = (x + 1.2, y + 0.4)
    plans = client.collect(Path, "/plan")
    feedback: list = []
    handle = _send(client, *target, feedback)
    result = client.result(handle.get_result_async(), 60)
    assert result.status == GoalStatus.STATUS_SUCCEEDED, result.result.error_msg
    assert result.result.error_code == 0
    assert feedback and feedback[0].current_pose.header.frame_id == "map"
    assert max(f.distance_remaining for f in feedback) > 0.5
    assert feedback[-1].navigation_time.sec + feedback[-1].navigation_time.nanosec > 0
    assert plans and plans[0][1].header.frame_id == "map" and plans[0][1].poses
    # amcl publishes after 0.25 m of motion (update_min_d); a no-motion update publishes now
    client.call(Empty, "/request_nomotion_update", Empty.Request())
    final = _amcl(client)
    assert until(lambda: math.dist(_xy(final[-1][1]), target) < 0.3, 5)


def test_a_goal_is_cancelled_by_another_client_and_preempted_by_a_new_one(tb3, client):
    from action_msgs.msg import GoalStatus
    from action_msgs.srv import CancelGoal

    # the other client found the server before the goals: on a loaded machine its discovery
    # may take longer than the fast robot takes to arrive
    with ros_client("tb3_other") as other:
        cancel = other.node.create_client(CancelGoal, "/navigate_to_pose/_action/cancel_goal")
        assert cancel.wait_for_service(timeout_sec=15)
        x, y = _xy(_amcl(client)[-1][1])
        first = _send(client, x + 8.0, y)
        time.sleep(0.5)
        second = _send(client, x + 8.0, y + 0.5)  # a new goal preempts: the first is aborted
        aborted = client.result(first.get_result_async(), 20)
        assert aborted.status == GoalStatus.STATUS_ABORTED and aborted.result.error_code == 0
        # anyone may cancel: zero id and stamp cancel all
        reply = other.result(cancel.call_async(CancelGoal.Request()), 15)
        assert reply.goals_canceling
    canceled = client.result(second.get_result_async(), 20)
    assert canceled.status == GoalStatus.STATUS_CANCELED


def test_goal_pose_starts_a_goal_as_bt_navigator_does(tb3, client):
    from action_msgs.msg import GoalStatus, GoalStatusArray
    from action_msgs.srv import CancelGoal
    from geometry_msgs.msg import PoseStamped

    x, y = _xy(_amcl(client)[-1][1])
    status = client.collect(GoalStatusArray, "/navigate_to_pose/_action/status")
    pub = client.node.create_publisher(PoseStamped, "/goal_pose", 10)
    goal = PoseStamped()
    goal.header.frame_id = "map"
    goal.pose.position.x, goal.pose.position.y, goal.pose.orientation.w = x + 1.5, y, 1.0
    executing = lambda: any(  # noqa: E731
        s.status == GoalStatus.STATUS_EXECUTING for _, m in status for s in m.status_list
    )
    assert until(lambda: (pub.publish(goal), executing())[1], 10)
    client.call(CancelGoal, "/navigate_to_pose/_action/cancel_goal", CancelGoal.Request())


@pytest.mark.parametrize(
    "args, said",
    [
        (["--robot", "rover"], "--robot must be astibot or turtlebot3"),
        (["--namespace", "/tb3_1"], "--namespace: only for --robot turtlebot3"),
        (["--robot", "turtlebot3", "--model", "waffle_pie"], "--model must be burger or waffle"),
        (["--robot", "turtlebot3", "--distro", "iron"], "--distro must be jazzy or humble"),
        (["--robot", "turtlebot3", "--namespace", "tb3 1"], "is not a ROS name"),
    ],
)
def test_bad_options_are_refused_in_one_line(args, said):
    run = subprocess.run(
        [sys.executable, "-m", "astiop", "sim", "node", *args],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert run.returncode != 0 and said in run.stderr and "Traceback" not in run.stderr
