"""`astiop sim node`'s camera on real ROS 2 (rclpy, DDS on the loopback): its frames on the
graph as a camera driver's, and read through the rclpy transport's gateway as the console
reads them (watched only while asked for)."""

from __future__ import annotations

import time

import pytest

from astiop.robot.factory import make_robot_gateway
from astiop.store import Store
from tests.ros import require_ros, ros_client, sim_node, until, whole_robot
from tests.ros.test_ros2_rclpy import settings

pytestmark = [pytest.mark.slow, pytest.mark.ros]


def test_the_sim_node_publishes_its_camera_and_the_console_reads_it(tmp_path):
    require_ros()
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import CompressedImage, Image

    with sim_node(speed=1.0), ros_client("camera_viewer") as client:
        raw = client.collect(Image, "/camera/image_raw", qos_profile_sensor_data)
        png = client.collect(
            CompressedImage, "/camera/image_raw/compressed", qos_profile_sensor_data
        )
        assert until(lambda: len(raw) >= 6 and png, 30), (len(raw), len(png))
        _, msg = raw[-1]
        assert (msg.height, msg.width, msg.encoding, msg.step) == (120, 160, "rgb8", 480)
        assert len(msg.data) == 120 * 160 * 3 and msg.header.frame_id == "camera"
        assert (
            png[-1][1].format == "rgb8; png compressed rgb8"
            and bytes(png[-1][1].data[1:4]) == b"PNG"
        )
        times = [t for t, _ in raw[-6:]]
        rate = (len(times) - 1) / (times[-1] - times[0])
        assert 3.0 < rate < 7.0, rate  # 5 Hz

        store = Store(tmp_path / "viewer.db")
        gateway = make_robot_gateway(settings(tmp_path), store)
        gateway.start()
        try:
            whole_robot(gateway)
            assert gateway.profile.name("camera") == "/camera/image_raw"
            first = gateway.camera()  # asked: watched from now on
            assert first.frame is None or first.frame.width == 160

            def framed():
                return gateway.camera().frame

            assert until(lambda: framed() is not None, 15)
            frame = framed()
            assert frame.pixels.shape == (120, 160, 3) and frame.encoding == "rgb8"
            age = gateway.state().t - frame.at
            assert -0.05 <= age < 1.0, age  # shown within a second of its arrival
            # the docked ASTIbot faces its charging station: green in the middle
            r, g, b = (int(v) for v in frame.pixels[60, 80])
            assert g > 1.5 * max(r, b), (r, g, b)
            backend = gateway.backend
            assert "/camera/image_raw" in backend._watching.watches
            time.sleep(3.5)  # not asked for WANTED_S and a graph read: no longer watched
            assert until(lambda: "/camera/image_raw" not in backend._watching.watches, 5)
        finally:
            gateway.close()
            store.close()
