"""`astiop sim node --robot turtlebot3` with Humble's names and under a namespace: one robot per
test (the TurtleBot3 of test_sim_tb3.py lives for its module, on another module's time)."""

from __future__ import annotations

import math

import pytest

from tests.ros import require_ros, ros_client, tb3_node, until
from tests.ros.test_sim_tb3 import START, _amcl, _graph_matches, _latest, _param, _send, _xy

pytestmark = [pytest.mark.slow, pytest.mark.ros]


@pytest.fixture
def client():
    require_ros()
    with ros_client("tb3_probe") as c:
        yield c


def test_humble_names_take_a_twist(client):
    require_ros()
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry

    with tb3_node(distro="humble", model="waffle", speed=8.0):
        _graph_matches(client, "humble", model="waffle")  # the camera's node and topic too
        topics = dict(client.node.get_topic_names_and_types())
        assert topics["/cmd_vel"] == ["geometry_msgs/msg/Twist"]
        assert "/cmd_vel_smoothed" not in topics  # humble's bringup remaps it to /cmd_vel
        assert _param(client, "/controller_server", "FollowPath.max_vel_x") == 0.22
        assert _param(client, "/global_costmap/global_costmap", "robot_radius") == 0.22
        odom = _latest(client, Odometry, "/odom")
        pub = client.node.create_publisher(Twist, "/cmd_vel", 10)
        turn = Twist()
        turn.angular.z = 1.0
        assert until(
            lambda: (pub.publish(turn), abs(odom[-1][1].twist.twist.angular.z) > 0.5)[1], 10
        )
        pub.publish(Twist())


def test_a_namespace_holds_every_name_and_frame(client):
    require_ros()
    from nav_msgs.msg import Odometry

    with tb3_node(namespace="/tb3_1", speed=8.0):
        _graph_matches(client, "jazzy", "/tb3_1")
        topics = dict(client.node.get_topic_names_and_types())
        assert "/odom" not in topics and "/tb3_1/odom" in topics
        odom = _latest(client, Odometry, "/tb3_1/odom")[-1][1]
        assert (odom.header.frame_id, odom.child_frame_id) == ("tb3_1/odom", "tb3_1/base_footprint")
        assert math.dist(_xy(_amcl(client, "/tb3_1")[-1][1]), START) < 0.05
        handle = _send(client, START[0] + 0.8, START[1], ns="/tb3_1")
        assert client.result(handle.get_result_async(), 40).status == 4  # SUCCEEDED


def test_a_waffle_shows_its_camera_a_burger_has_none(client):
    """The Waffle's /camera/image_raw (turtlebot3_simulations' camera_rgb_frame), drawn from the
    warehouse as the ASTIbot's is; a burger has no camera topic at all."""
    require_ros()
    from sensor_msgs.msg import Image

    with tb3_node(model="waffle", speed=8.0):
        frames = _latest(client, Image, "/camera/image_raw", timeout=20.0)
        image = frames[-1][1]
        assert (image.width, image.height, image.encoding) == (320, 180, "rgb8")
        assert image.header.frame_id == "camera_rgb_frame"
        assert len(image.data) == 320 * 180 * 3 and len(set(bytes(image.data))) > 4  # a view
    with tb3_node(model="burger", speed=8.0):
        _graph_matches(client, "jazzy")
        # the graph matched (every node up): nothing publishes a camera (this client's own
        # subscription from the Waffle keeps the topic's name on the graph)
        assert client.node.count_publishers("/camera/image_raw") == 0
