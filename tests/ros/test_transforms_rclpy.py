"""The transform table on rclpy's own message objects (tf2_msgs, where ROS 2 is installed)
folds as on their dicts (tests/unit/test_transforms.py)."""

from __future__ import annotations

import math

import pytest

from astiop.ros2.transforms import TransformTable, map_pose
from tests.unit.test_transforms import close, msg, tf


def test_rclpy_messages_fold_as_their_dicts_do():
    msgs = pytest.importorskip("tf2_msgs.msg")
    from astiop.ros2.message_objects import to_message

    sent = msg(tf("map", "odom", 2.0, -1.0, math.pi), tf("odom", "base_footprint", 0.5, 0.5, 0))
    table = TransformTable()
    table.fold_object(to_message(msgs.TFMessage, sent), at=0.0)
    out = table.message(now=0.0)
    assert [t["child_frame_id"] for t in out["transforms"]] == ["odom", "base_footprint"]
    assert close(map_pose([out])[0], (1.5, -1.5, math.pi))
