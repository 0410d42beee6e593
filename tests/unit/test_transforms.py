"""The map pose from TF: 2D compositions checked against poses computed by hand, the table that
keeps the latest transform per (parent, child) of a high-rate /tf, the base frame found from the
transforms seen, and the state's pose in the issue's order (Pose2D > amcl > /tf > odometry),
kept fresh between amcl's updates by map → odom ∘ odom → base."""

from __future__ import annotations

import math

import pytest

from astiop.ros2.profile import match_profile
from astiop.ros2.transforms import (
    MAX_PAIRS,
    TransformTable,
    compose,
    inverse,
    map_pose,
    yaw_of,
)
from astiop.transports.state import from_messages
from tests.unit.test_profile import tb3_graph

HALF_PI = math.pi / 2


def q(yaw: float) -> dict:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def tf(parent: str, child: str, x: float, y: float, yaw: float, z: float = 0.0) -> dict:
    return {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": parent},
        "child_frame_id": child,
        "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": q(yaw)},
    }


def msg(*transforms: dict) -> dict:
    return {"transforms": list(transforms)}


def close(a, b, tol=1e-9) -> bool:
    return math.dist(a[:2], b[:2]) < tol and abs(math.remainder(a[2] - b[2], 2 * math.pi)) < tol


def test_compositions_match_the_poses_worked_by_hand():
    # odom turned a quarter left at (1, 2): a metre ahead in odom is (1, 3) in the map
    assert close(compose((1.0, 2.0, HALF_PI), (1.0, 0.0, 0.0)), (1.0, 3.0, HALF_PI))
    # odom turned half round at (2, -1); the base at (0.5, 0.5) facing left in it
    assert close(compose((2.0, -1.0, math.pi), (0.5, 0.5, HALF_PI)), (1.5, -1.5, -HALF_PI))
    # the inverse undoes: (3, 0) facing left, seen from itself, puts the origin at (0, 3)
    assert close(inverse((3.0, 0.0, HALF_PI)), (0.0, 3.0, -HALF_PI))
    a = (0.3, -4.2, 2.5)
    assert close(compose(a, inverse(a)), (0.0, 0.0, 0.0))
    assert yaw_of(q(2.5)) == pytest.approx(2.5) and yaw_of({"w": "bad"}) == 0.0


def test_the_map_pose_is_map_odom_then_odom_base_from_their_own_publishers():
    amcl = msg(tf("map", "odom", 2.0, -1.0, math.pi))
    odometry = msg(tf("odom", "base_footprint", 0.5, 0.5, HALF_PI))
    wheels = msg(tf("base_link", "wheel_left_link", 0.0, 0.08, 0.0, 0.023))
    static = msg(tf("base_footprint", "base_link", 0.0, 0.0, 0.0, 0.010))
    pose, base = map_pose([static, amcl, odometry, wheels])
    assert base == "base_footprint" and close(pose, (1.5, -1.5, -HALF_PI))
    # a robot whose odometry's child is base_link, its frames with a leading slash (ROS 1 style)
    pose, base = map_pose([msg(tf("/map", "/odom", 1.0, 2.0, HALF_PI)),
                           msg(tf("/odom", "/base_link", 1.0, 0.0, 0.0))])  # fmt: skip
    assert base == "base_link" and close(pose, (1.0, 3.0, HALF_PI))
    # under a namespace's frame prefix (turtlebot3_node: "tb3_1/odom")
    prefixed = [msg(tf("map", "tb3_1/odom", 1.0, 2.0, HALF_PI)),
                msg(tf("tb3_1/odom", "tb3_1/base_footprint", 1.0, 0.0, 0.0))]  # fmt: skip
    assert map_pose(prefixed)[1] == "tb3_1/base_footprint"


def test_no_map_frame_no_map_pose_and_odometry_completes_a_chain_that_stops_at_odom():
    assert map_pose([msg(tf("odom", "base_link", 1.0, 0.0, 0.0))]) is None
    assert map_pose([None, {}]) is None
    odom = {
        "header": {"frame_id": "odom"},
        "child_frame_id": "base_link",
        "pose": {"pose": {"position": {"x": 1.0, "y": 0.0}, "orientation": q(0.0)}},
    }
    pose, base = map_pose([msg(tf("map", "odom", 1.0, 2.0, HALF_PI))], odom)
    assert base == "base_link" and close(pose, (1.0, 3.0, HALF_PI))
    # a cycle (a malformed tree) and NaNs end, with no pose
    cycle = msg(tf("a", "base_link", 0, 0, 0), tf("base_link", "a", 0, 0, 0))
    assert map_pose([cycle]) is None
    assert map_pose([msg(tf("map", "base_link", math.nan, 0.0, 0.0))]) is None


def test_the_table_keeps_the_latest_transform_per_pair_and_forgets_the_silent():
    table = TransformTable(stale_s=3.0)
    for i in range(100):  # a 50 Hz /tf: two seconds of odometry, one pair
        table.fold(msg(tf("odom", "base_footprint", i * 0.01, 0.0, 0.0)), at=i * 0.02)
    table.fold(msg(tf("map", "odom", 4.0, 4.0, 0.0)), at=0.0)
    out = table.message(now=2.0)
    assert len(out["transforms"]) == 2
    assert close(map_pose([out])[0], (4.99, 4.0, 0.0))
    assert len(table.message(now=3.5)["transforms"]) == 1  # amcl silent 3.5 s: map → odom gone
    assert map_pose([table.message(now=3.5)]) is None
    static = TransformTable(stale_s=None)
    static.fold(msg(tf("base_footprint", "base_link", 0.0, 0.0, 0.0)), at=0.0)
    assert len(static.message(now=1e6)["transforms"]) == 1 and TransformTable().message(0) is None
    flood = TransformTable()
    flood.fold(msg(*(tf("odom", f"f{i}", 0, 0, 0) for i in range(MAX_PAIRS + 10))), at=0.0)
    assert len(flood.message(0.0)["transforms"]) == MAX_PAIRS  # bounded


ODOM = {
    "header": {"frame_id": "odom"},
    "child_frame_id": "base_footprint",
    "pose": {"pose": {"position": {"x": 0.6, "y": 0.0}, "orientation": q(0.0)}},
    "twist": {"twist": {"linear": {"x": 0.2}, "angular": {"z": 0.0}}},
}
AMCL = {"pose": {"pose": {"position": {"x": 4.4, "y": 4.0}, "orientation": q(0.0)}}}
TF = msg(tf("map", "odom", 4.0, 4.0, 0.0), tf("odom", "base_footprint", 0.6, 0.0, 0.0))


def test_an_amcl_pose_is_advanced_by_map_odom_and_odometry_between_its_updates():
    profile = match_profile(tb3_graph())
    assert profile.name("pose") == "/amcl_pose" and "/tf" in profile.state_topics()
    assert "map → odom ∘ odom → base" in profile.matches["pose"].why
    st = from_messages(0.0, {"/amcl_pose": AMCL, "/tf": TF, "/odom": ODOM}, profile=profile)
    assert (st.pose.x, st.pose.y) == pytest.approx((4.6, 4.0)), "not amcl's last, 0.2 m behind"
    # TF has no map frame yet (amcl not localised): amcl's own pose, never odometry's origin
    odom_only = msg(tf("odom", "base_footprint", 0.6, 0.0, 0.0))
    st = from_messages(0.0, {"/amcl_pose": AMCL, "/tf": odom_only}, profile=profile)
    assert (st.pose.x, st.pose.y) == pytest.approx((4.4, 4.0))
    # /tf has map → odom only: the odometry message completes the chain
    st = from_messages(0.0, {"/amcl_pose": AMCL, "/tf": msg(TF["transforms"][0]), "/odom": ODOM},
                       profile=profile)  # fmt: skip
    assert (st.pose.x, st.pose.y) == pytest.approx((4.6, 4.0))


def test_a_robot_without_amcl_has_its_pose_from_tf_and_the_profile_says_so():
    profile = match_profile(tb3_graph(amcl_pose=True))
    assert profile.name("pose") == "/tf" and profile.kind("pose") == "topic"
    assert "map → base_footprint or base_link" in profile.matches["pose"].why
    st = from_messages(0.0, {"/tf": TF, "/odom": ODOM}, profile=profile)
    assert (st.pose.x, st.pose.y) == pytest.approx((4.6, 4.0))
    # no localiser at all: the odometry's pose, from /tf or else /odom
    odom_only = msg(tf("odom", "base_footprint", 0.6, 0.1, 0.0))
    st = from_messages(0.0, {"/tf": odom_only, "/odom": ODOM}, profile=profile)
    assert (st.pose.x, st.pose.y) == pytest.approx((0.6, 0.1))
    st = from_messages(0.0, {"/odom": ODOM}, profile=profile)
    assert (st.pose.x, st.pose.y) == pytest.approx((0.6, 0.0))


def test_tf_is_watched_only_for_a_pose_built_from_it():
    astibot = match_profile(tb3_graph(amcl_pose=True, tf=True))
    assert astibot.name("pose") == "/odom" and "/tf" not in astibot.state_topics()
    from astiop.ros2.catalog import astibot_catalog

    robot = match_profile(astibot_catalog())
    assert robot.name("pose") == "/robot_pose" and robot.has("transforms")
    assert "/tf" not in robot.state_topics() and "/tf_static" not in robot.state_topics()
