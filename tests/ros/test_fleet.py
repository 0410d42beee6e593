"""A fleet on one ROS 2 domain, a robot per namespace: two TurtleBot3 programs under /tb3_1 and
/tb3_2, found with --fleet auto or listed in the settings, each addressed by --robot-name, and
`astiop estop --all` stopping both at once (each one's Nav2 goal cancelled)."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from astiop.config import ConfigError, load_settings
from astiop.robot.fleet import FleetError, namespaces, robot_settings
from astiop.robot.lease import Lease, lease_key
from astiop.store import Store
from tests.ros import SimNode, require_ros, ros_client

pytestmark = [pytest.mark.slow, pytest.mark.ros]
TB3 = ("--robot", "turtlebot3", "--model", "burger", "--distro", "jazzy")


def test_a_robot_of_the_fleet_is_its_namespace_and_profile(tmp_path):
    fleet = {"robots": [{"name": "left", "namespace": "/tb3_1"},
                        {"name": "right", "namespace": "/tb3_2", "profile": "turtlebot3_waffle"}]}  # fmt: skip
    settings = load_settings({"fleet": fleet}, env={}, path=tmp_path / "none.toml")
    right = robot_settings(settings, "right")
    assert right.robot.namespace == "/tb3_2" and right.robot.profile == "turtlebot3_waffle"
    assert robot_settings(settings, "left").robot.profile == "auto"
    with pytest.raises(FleetError, match="no robot named 'middle' .*left, right"):
        robot_settings(settings, "middle")
    auto = load_settings({"fleet": {"discover": "auto"}}, env={}, path=tmp_path / "none.toml")
    assert robot_settings(auto, "tb3_7").robot.namespace == "/tb3_7"
    with pytest.raises(ConfigError, match="two robots of the fleet have the namespace"):
        load_settings(
            {"fleet": {"robots": [{"name": "a", "namespace": "/x"}, {"name": "b", "namespace": "/x"}]}},
            env={}, path=tmp_path / "none.toml",
        )  # fmt: skip


def test_robot_namespaces_are_those_with_a_velocity_command_and_a_pose():
    from tests.unit.test_profile import tb3_graph

    one, two = tb3_graph("/tb3_1"), tb3_graph("/tb3_2")
    one.topics.update(two.topics)
    one.topics["/amcl/transition_event"] = one.topics["/tb3_1/odom"]  # a Nav2 node's, no robot
    assert namespaces(one) == ["/tb3_1", "/tb3_2"]


@contextlib.contextmanager
def two_robots():
    from tests.ros import quiet_domain

    quiet_domain()
    nodes = [SimNode(seed=i, speed=4.0, robot_args=(*TB3, "--namespace", f"/tb3_{i}"))
             for i in (1, 2)]  # fmt: skip
    try:
        for node in nodes:
            node.wait_ready()
        yield nodes
    finally:
        for node in nodes:
            node.stop()


def astiop(db: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    cli = [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2"]
    cli += ["--ros2-transport", "rclpy"]
    return subprocess.run([*cli, *args], capture_output=True, text=True, timeout=timeout)


def test_two_turtlebot3s_are_found_read_addressed_and_stopped_at_once(tmp_path):
    require_ros()
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient

    db = tmp_path / "fleet.db"
    with two_robots(), ros_client("someone_else") as client:
        out = astiop(db, "--fleet", "auto", "fleet", "list", "--json")
        assert out.returncode == 0, out.stderr[-2000:]
        rows = {r["name"]: r for r in json.loads(out.stdout)}
        assert set(rows) == {"tb3_1", "tb3_2"}, rows
        for name, row in rows.items():
            assert row["namespace"] == "/" + name and row["make"] == "turtlebot3_burger", row
            assert row["state"] == "idle" and 1.0 < row["battery_percent"] <= 100.0, row
            assert abs(row["x_m"] - 4.0) < 0.1 and abs(row["y_m"] - 4.0) < 0.1, row

        out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_2", "robot", "profile", "--json")
        assert out.returncode == 0, out.stderr[-2000:]
        assert json.loads(out.stdout)["roles"]["navigation"]["name"] == "/tb3_2/navigate_to_pose"

        # a goal on each, another client's: --all cancels both, each through its own names
        handles = []
        for ns in ("/tb3_1", "/tb3_2"):
            action = ActionClient(client.node, NavigateToPose, f"{ns}/navigate_to_pose")
            assert action.wait_for_server(timeout_sec=15)
            goal = NavigateToPose.Goal()
            goal.pose.header.frame_id = "map"
            goal.pose.pose.position.x, goal.pose.pose.position.y = 30.0, 4.0
            goal.pose.pose.orientation.w = 1.0
            handles.append(client.result(action.send_goal_async(goal)))
        assert all(h.accepted for h in handles)
        # asked for now: Kilted's rclpy keeps a goal's result 10 s only (server.py result_timeout)
        results = [handle.get_result_async() for handle in handles]
        pressed = time.monotonic()
        out = astiop(db, "--fleet", "auto", "estop", "--all")
        took = time.monotonic() - pressed
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        assert "tb3_1: E-STOP engaged" in out.stdout and "tb3_2: E-STOP engaged" in out.stdout
        for result in results:
            done = client.result(result, 20)
            assert done.status == GoalStatus.STATUS_CANCELED, (done.status, took)
        # latched for every process on the database: one robot's command is refused
        out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "exec",
                     "ros2 topic pub --once /tb3_1/cmd_vel geometry_msgs/msg/TwistStamped "
                     "'{twist: {linear: {x: 0.1}}}'", "--yes")  # fmt: skip
        assert out.returncode != 0 and "E-STOP" in out.stdout + out.stderr, out
        out = astiop(db, "--fleet", "auto", "estop", "--release", "--all", "--yes")
        assert out.returncode == 0 and "released: tb3_1, tb3_2" in out.stdout, out

        # one robot's E-STOP latches that robot alone
        out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "estop")
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        store = Store(db)
        assert store.latched_robots() == ["/tb3_1"] and store.estop_latch() is None
        out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "exec",
                     "ros2 topic pub --once /tb3_1/cmd_vel geometry_msgs/msg/TwistStamped "
                     "'{twist: {linear: {x: 0.1}}}'", "--yes")  # fmt: skip
        assert out.returncode != 0 and "E-STOP" in out.stdout + out.stderr, out

        # another console controls tb3_2: this one moves it only once it takes control
        holder = Lease(Store(db), lease_key("/tb3_2", os.environ["ROS_DOMAIN_ID"]), "tb3_2",
                       "another console")  # fmt: skip
        assert holder.take() is None
        drive = ("--fleet", "auto", "--robot-name", "tb3_2", "exec", "ros2 topic pub --once "
                 "/tb3_2/cmd_vel geometry_msgs/msg/TwistStamped '{twist: {linear: {x: 0.1}}}'",
                 "--yes")  # fmt: skip
        out = astiop(db, *drive)
        assert out.returncode != 0, out
        assert "tb3_2 is controlled by another console" in out.stdout + out.stderr, out
        out = astiop(db, "--take", *drive)
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        assert holder.holder() is None  # taken, then let go when that command ended
        holder.release()
        holder.store.close()
        out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "estop", "--release", "--yes")
        assert out.returncode == 0 and "E-STOP released (tb3_1)" in out.stdout, out
        assert store.latched_robots() == []
        store.close()


def test_a_bad_robot_name_and_one_robot_released_from_every_robots_stop(tmp_path):
    db = tmp_path / "f.db"
    out = astiop(db, "--fleet", "auto", "--robot-name", "a/b", "robot", "profile")
    assert out.returncode == 2 and "'a/b' is no robot name" in out.stderr, out.stderr
    store = Store(db)
    store.latch_estop("estop --all")  # every robot's: one of them is not let go alone
    out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "estop", "--release", "--yes")
    assert (
        out.returncode == 2
        and ("the E-STOP of every robot on this database holds tb3_1: astiop estop --release --all")
        in out.stderr
    ), out.stderr
    assert store.estop_latch() is not None
    store.close()
    out = astiop(db, "--fleet", "auto", "--robot-name", "tb3_1", "estop", "--all")
    assert out.returncode == 2 and "leave out --robot-name" in out.stderr, out.stderr


def test_a_fleet_robots_parameters_are_astiops_under_its_namespace():
    """`ros2 param set /astibot_2/astibot_base max_linear_speed 0.5` under --robot-name
    astibot_2: checked by astiop's limits whether or not the robot's parameters were read yet,
    and a parameter astiop does not write says which it does, in one line."""
    from astiop.ros2.profile_types import ProfileSpec
    from astiop.ros2.validation import validate
    from astiop.transports.live_catalog import describe_graph, nothing_listed

    fixed = ProfileSpec(namespace="/astibot_2")
    lists = nothing_listed()
    lists["node"] = [("/astibot_2/astibot_base", ""), ("/astibot_2/navigator", "")]
    not_read = describe_graph(lists, fixed)
    read = describe_graph(
        {
            **lists,
            "param": [
                ("/astibot_2/astibot_base max_linear_speed", "double"),
                ("/astibot_2/navigator goal_tolerance", "double"),
            ],
        },
        fixed,
    )
    for catalog in (not_read, read):
        ok = validate("ros2 param set /astibot_2/astibot_base max_linear_speed 0.5", catalog)
        assert ok.valid and ok.message == {"value": 0.5}, ok.reason
        too_fast = validate("ros2 param set /astibot_2/astibot_base max_linear_speed 5", catalog)
        assert too_fast.reason == "max_linear_speed must be within 0.05..1.4"
        fixed_one = validate("ros2 param set /astibot_2/navigator goal_tolerance 5.0", catalog)
        assert fixed_one.reason == "parameter goal_tolerance of /astibot_2/navigator is read-only"
