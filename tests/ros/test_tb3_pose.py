"""The map pose of a robot under Nav2, over real DDS through rclpy: while a TurtleBot3 drives,
astiop's pose follows the robot (amcl's map → odom on /tf ∘ the odometry), where /amcl_pose
alone lags by up to update_min_d (0.25 m); and a robot with no amcl but a map → base chain on
/tf has its pose from /tf, its profile saying so.

The TurtleBot3 program's truth: its odometry's origin is START in the map (`node.py`), so the
robot's map pose is START ∘ /odom's pose, read here by the test's own subscription."""

from __future__ import annotations

import math
import time

import pytest

from astiop.ros2.transforms import compose, yaw_of
from tests.ros import require_ros, ros_client, until
from tests.ros.test_tb3_operated import gateway_on, settings

pytestmark = [pytest.mark.slow, pytest.mark.ros]
START = (4.0, 4.0, 0.0)  # astiop/robot_programs/turtlebot3/node.py
LATENCY_S = 1.5  # a loaded machine (two pytest workers) reads its topics that late


def _turn(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def _xy_yaw(pose) -> tuple[float, float, float]:
    return (pose.position.x, pose.position.y, yaw_of(_q(pose.orientation)))


def _q(o) -> dict:
    return {"x": o.x, "y": o.y, "z": o.z, "w": o.w}


def test_the_pose_of_a_driving_turtlebot3_keeps_up_where_amcl_pose_lags(tmp_path):
    require_ros()
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from nav_msgs.msg import Odometry
    from rclpy.qos import DurabilityPolicy, QoSProfile

    from tests.ros import tb3_node

    latched = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    # real time: the robot at 0.2 m/s, as an operator sees it (not sped up 8 times)
    with tb3_node(speed=1.0), ros_client("pose_truth") as client:
        odom = client.collect(Odometry, "/odom")
        amcl = client.collect(PoseWithCovarianceStamped, "/amcl_pose", latched)
        gateway, store = gateway_on(tmp_path)
        try:
            assert gateway.profile.name("pose") == "/amcl_pose"
            # /tf's publisher may be discovered after the pose's (a loaded machine): the graph
            # is read again when it changes
            assert until(lambda: "/tf" in gateway.catalog.state_topics(), 15), gateway.catalog

            assert until(lambda: odom and amcl, 10)
            ours, amcl_only, headings, amcl_headings = [], [], [], []
            # straight (a turn would update amcl sooner), then a turn on the spot
            for vx, wz, for_s in ((0.2, 0.0, 5.0), (0.0, 0.5, 2.0)):
                t_end = time.monotonic() + for_s
                while time.monotonic() < t_end:
                    gateway.drive(vx, 0.0, wz)
                    time.sleep(0.05)
                    pose, now = gateway.state().pose, time.monotonic()
                    truth = compose(START, _xy_yaw(odom[-1][1].pose.pose))
                    last = _xy_yaw(amcl[-1][1].pose.pose)
                    # astiop's: where the robot was at some moment of the last LATENCY_S (its
                    # topics are taken ten times a second, on a loaded machine later)
                    recent = [compose(START, _xy_yaw(m.pose.pose)) for t, m in odom[-80:]
                              if t >= now - LATENCY_S] or [truth]  # fmt: skip
                    ours.append(min(math.dist((pose.x, pose.y), p[:2]) for p in recent))
                    headings.append(min(_turn(pose.theta, p[2]) for p in recent))
                    # /amcl_pose's: against the truth now, as the Dashboard showed it
                    amcl_only.append(math.dist(last[:2], truth[:2]))
                    amcl_headings.append(_turn(last[2], truth[2]))
            gateway.drive(0.0, 0.0, 0.0)
            moved = math.dist(compose(START, _xy_yaw(odom[-1][1].pose.pose))[:2], START[:2])
            print(f"\nmoved {moved:.2f} m; astiop's pose off by max {max(ours):.3f} m "
                  f"(mean {sum(ours) / len(ours):.3f}), {max(headings):.3f} rad; /amcl_pose "
                  f"alone by max {max(amcl_only):.3f} m (mean "
                  f"{sum(amcl_only) / len(amcl_only):.3f}), {max(amcl_headings):.3f} rad")  # fmt: skip
            assert moved > 0.6, moved
            assert max(ours) < 0.1 and max(headings) < 0.1, (ours, headings)
            # what the Dashboard showed before: amcl's pose, a quarter metre or 0.2 rad behind
            assert max(amcl_only) > 0.15 and max(amcl_headings) > 0.12, (amcl_only, amcl_headings)
        finally:
            gateway.close()
            store.close()


def test_a_robot_without_amcl_has_its_map_pose_from_tf(tmp_path):
    """A robot of the test's own: map → odom (a localiser) and odom → base_link on /tf."""
    require_ros()
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    from astiop.store import Store
    from tests.ros import quiet_domain

    def transform(parent, child, x, y, yaw):
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = parent, child
        t.transform.translation.x, t.transform.translation.y = x, y
        t.transform.rotation.z, t.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        return t

    quiet_domain()
    with ros_client("tf_only_robot") as robot:
        pub = robot.node.create_publisher(TFMessage, "/tf", 10)
        odom_x = [0.0]

        sent: list[float] = []  # every odom x published: astiop's pose is one of them

        def tick():
            odom_x[0] += 0.01
            sent.append(odom_x[0])
            pub.publish(TFMessage(transforms=[transform("map", "odom", 1.0, 2.0, math.pi / 2)]))
            pub.publish(TFMessage(transforms=[transform("odom", "base_link", odom_x[0], 0, 0)]))

        robot.node.create_timer(0.05, tick)
        from astiop.robot.factory import make_robot_gateway

        store = Store(tmp_path / "tf.db")
        gateway = make_robot_gateway(settings(tmp_path), store)
        gateway.start()
        try:
            assert until(lambda: gateway.profile.name("pose") == "/tf", 20), gateway.profile
            assert "map → base_footprint or base_link" in gateway.profile.matches["pose"].why
            assert until(lambda: gateway.state().pose is not None, 20)
            pose = gateway.state().pose
            # map → odom (1, 2, a quarter left) ∘ odom → base_link (x, 0): (1, 2 + x), facing y,
            # for an x that was published (however late it was read on a loaded machine)
            assert abs(pose.x - 1.0) < 0.01, pose
            assert any(abs(pose.y - (2.0 + x)) < 1e-6 for x in list(sent)), (pose, sent[-5:])
            assert abs(pose.theta - math.pi / 2) < 1e-6
        finally:
            gateway.close()
            store.close()
