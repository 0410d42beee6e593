"""The CLI transport against robots astiop did not write, on real DDS: the emulated `ros2` in
its DDS mode (`astiop emulate-ros2 --dds`: ros2cli's argument parsing, each verb run over rclpy
against the robot on the domain, printed as ros2cli prints it) in front of the TurtleBot3
program, jazzy, no profile file. Its roles are found from `ros2 ... list`; questions are
answered with what it published; a goal by coordinates goes out as `ros2 action send_goal` and
arrives; `astiop estop` stops it with no /stop service (every Nav2 goal cancelled, a zero
TwistStamped), under a namespace too."""

from __future__ import annotations

import contextlib
import json
import math
import subprocess
import sys

import pytest

from tests.emulator import emulated_robot, on_path, ros2_calls
from tests.ros import battery_answer_agrees, require_ros, ros_client, until
from tests.ros.test_tb3_operated import ask, gateway_on

pytestmark = [pytest.mark.slow, pytest.mark.ros]


@contextlib.contextmanager
def dds_ros2(monkeypatch, namespace: str = ""):
    """The DDS-mode `ros2` on PATH, once it has discovered the robot's Nav2 action."""
    with emulated_robot(dds=True) as folder:
        on_path(monkeypatch, folder)
        action = f"{namespace}/navigate_to_pose"

        def listed() -> bool:
            out = subprocess.run(["ros2", "action", "list"], capture_output=True, text=True)
            return action in out.stdout.split()

        assert until(listed, 30, step=0.5), f"{action} not discovered"
        yield folder


def astiop_cli(tmp_path, *args: str, namespace: str = "") -> subprocess.CompletedProcess:
    argv = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "cli.db"), "--robot", "ros2"]
    argv += ["--ros2-transport", "cli", *(("--namespace", namespace) if namespace else ())]
    return subprocess.run([*argv, *args], capture_output=True, text=True, timeout=90)


def test_the_dds_ros2_parses_like_ros2cli_and_says_what_it_cannot_run(monkeypatch):
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=4.0), dds_ros2(monkeypatch) as folder:
        bad = subprocess.run(["ros2", "topic", "echo"], capture_output=True, text=True)
        assert bad.returncode == 2 and "usage: ros2 topic echo" in bad.stderr
        unknown = subprocess.run(
            ["ros2", "topic", "pub", "--once", "/x", "no_such_pkg/msg/Nothing", "{}"],
            capture_output=True, text=True,
        )  # fmt: skip
        assert unknown.returncode == 1
        assert unknown.stderr.strip() == "The passed message type is invalid"
        out = subprocess.run(["ros2", "topic", "info", "/cmd_vel"], capture_output=True, text=True)
        assert out.stdout.splitlines()[0] == "Type: geometry_msgs/msg/TwistStamped"
        assert ["topic", "info", "/cmd_vel"] in ros2_calls(folder)


def test_a_turtlebot3_through_the_ros2_cli_is_profiled_answered_and_sent(monkeypatch, tmp_path):
    require_ros()
    from std_srvs.srv import Trigger

    from tests.ros import tb3_node

    def listed() -> str:
        return subprocess.run(["ros2", "service", "list"], capture_output=True, text=True).stdout

    with tb3_node(speed=8.0), dds_ros2(monkeypatch) as folder, ros_client("a_console") as other:
        # another console's kept /stop client: `ros2 service list` names /stop by it (rmw lists
        # clients too), yet the TurtleBot3 serves none
        other.node.create_client(Trigger, "/stop")
        assert until(lambda: "/stop" in listed().split(), 15)
        out = astiop_cli(tmp_path, "robot", "profile", "--json")
        assert out.returncode == 0, out.stderr
        roles = json.loads(out.stdout)["roles"]
        names = {r: roles[r]["name"] for r in ("pose", "battery", "scan", "map", "navigation")}
        assert names == {"pose": "/amcl_pose", "battery": "/battery_state", "scan": "/scan",
                         "map": "/map", "navigation": "/navigate_to_pose"}  # fmt: skip
        assert roles["velocity_command"]["name"] == "/cmd_vel"
        assert roles["velocity_command"]["type"] == "geometry_msgs/msg/TwistStamped"
        assert not roles["stop"]["name"]

        gateway, store = gateway_on(tmp_path, ros2_transport="cli")
        try:
            assert type(gateway.backend).__name__ == "Ros2Backend"  # the CLI transport
            assert until(lambda: gateway.map_geometry() is not None, 15)  # latched /map, echoed
            # no status topic of its own: its state word follows Nav2's goal status stream
            assert until(lambda: gateway.state().state_word == "idle", 15), gateway.state()
            result, _ = ask(gateway, "where is the robot?")
            echo = gateway.run("ros2 topic echo /amcl_pose --once").values["pose"]["pose"]
            assert f"x {echo['position']['x']:.2f} m" in result.answer, result.answer
            assert f"y {echo['position']['y']:.2f} m" in result.answer, result.answer
            battery_answer_agrees(
                gateway, lambda: ask(gateway, "what is the battery level?")[0].answer
            )

            start = gateway.state().pose
            target = (start.x + 1.0, start.y + 0.5)
            result, follow = ask(gateway, f"go to x {target[0]:.1f} y {target[1]:.1f}")
            assert result.commands[0].command.startswith(
                "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose"
            ), result.commands
            assert result.started.startswith("goal accepted"), result.answer
            assert "succeeded" in follow or follow.startswith("arrived"), follow
            assert until(lambda: math.dist(_xy(gateway), target) < 0.3, 10), _xy(gateway)
            assert until(lambda: gateway.state().state_word == "idle", 10), gateway.state()

            # a goal running says "navigating"; cancelled (its client's Ctrl-C), idle again
            far = "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
            far += "'{pose: {header: {frame_id: map}, pose: {position: {x: 12.0, y: 4.0}, "
            far += "orientation: {w: 1.0}}}}'"
            ran = gateway.run(far, confirm=lambda _c: True)
            assert ran.values["accepted"], ran.output
            assert until(lambda: gateway.state().state_word == "navigating", 10), gateway.state()
            gateway.cancel_goals()
            assert until(lambda: gateway.state().state_word == "idle", 15), gateway.state()
            sent = [c for c in ros2_calls(folder) if c[:2] == ["action", "send_goal"]]
            assert sent and sent[-1][2:4] == [
                "/navigate_to_pose",
                "nav2_msgs/action/NavigateToPose",
            ]

            # "stop the robot": its goals cancelled through the action's hidden cancel service
            ran = gateway.run(far, confirm=lambda _c: True)
            assert until(lambda: gateway.state().state_word == "navigating", 10), gateway.state()
            result, _ = ask(gateway, "stop the robot")
            assert result.commands[0].command.startswith(
                "ros2 service call /navigate_to_pose/_action/cancel_goal"
            ), result.commands
            assert all(c.executed and not c.error for c in result.commands), result.commands
            assert until(lambda: gateway.state().state_word == "idle", 15), gateway.state()
            # the E-STOP of a console that read the graph: no stop service is no failure
            assert gateway.estop() == []
        finally:
            gateway.close()
            store.close()


def _xy(gateway) -> tuple[float, float]:
    pose = gateway.state().pose
    return (pose.x, pose.y)


def _estop_stops_a_running_goal(tmp_path, folder, namespace: str) -> None:
    """Another client's NavigateToPose goal running, `astiop estop` through the CLI: the goal
    is CANCELED (not SUCCEEDED), the base stops, and a zero TwistStamped went out."""
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from nav_msgs.msg import Odometry
    from rclpy.action import ActionClient

    with ros_client("someone_else") as client:
        odom = client.collect(Odometry, f"{namespace}/odom")
        action = ActionClient(client.node, NavigateToPose, f"{namespace}/navigate_to_pose")
        assert action.wait_for_server(timeout_sec=15)
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        # 24 m ahead (~27 s at 4x): a cold `astiop estop` through the CLI lands first, loaded too
        goal.pose.pose.position.x, goal.pose.pose.position.y = 28.0, 4.0
        goal.pose.pose.orientation.w = 1.0
        handle = client.result(action.send_goal_async(goal))
        assert handle.accepted
        assert until(lambda: odom and abs(odom[-1][1].twist.twist.linear.x) > 0.05, 15)
        out = astiop_cli(tmp_path, "estop", namespace=namespace)
        # 0: no failure said (a /stop it lacks is said absent, not waited out as a failure)
        assert out.returncode == 0, out.stdout + out.stderr
        result = client.result(handle.get_result_async(), 20)
        assert result.status == GoalStatus.STATUS_CANCELED, result.status
        assert until(lambda: abs(odom[-1][1].twist.twist.linear.x) < 0.01, 5)
    calls = ros2_calls(folder)
    cancel = f"{namespace}/navigate_to_pose/_action/cancel_goal"
    assert ["service", "call", cancel, "action_msgs/srv/CancelGoal", "{}"] in calls, calls
    zero = [c for c in calls if c[:2] == ["topic", "pub"] and f"{namespace}/cmd_vel" in c]
    assert zero and "geometry_msgs/msg/TwistStamped" in zero[-1], calls


def test_the_estop_through_the_ros2_cli_cancels_every_nav2_goal(monkeypatch, tmp_path):
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=4.0), dds_ros2(monkeypatch) as folder:
        _estop_stops_a_running_goal(tmp_path, folder, "")


def test_a_turtlebot3_under_a_namespace_through_the_ros2_cli(monkeypatch, tmp_path):
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=4.0, namespace="/tb3_1"), dds_ros2(monkeypatch, "/tb3_1") as folder:
        out = astiop_cli(tmp_path, "robot", "profile", "--json", namespace="/tb3_1")
        assert out.returncode == 0, out.stderr
        profile = json.loads(out.stdout)
        assert profile["namespace"] == "/tb3_1"
        roles = profile["roles"]
        assert roles["pose"]["name"] == "/tb3_1/amcl_pose"
        assert roles["battery"]["name"] == "/tb3_1/battery_state"
        assert roles["velocity_command"]["name"] == "/tb3_1/cmd_vel"
        assert roles["navigation"]["name"] == "/tb3_1/navigate_to_pose"
        _estop_stops_a_running_goal(tmp_path, folder, "/tb3_1")


def test_the_astibot_program_through_the_ros2_cli(monkeypatch, tmp_path):
    """`astiop sim node` on real DDS through the CLI: its own names, and its /stop answered."""
    require_ros()
    from tests.ros import sim_node

    with sim_node(speed=4.0), dds_ros2(monkeypatch) as folder:
        out = astiop_cli(tmp_path, "robot", "profile", "--json")
        assert out.returncode == 0, out.stderr
        roles = json.loads(out.stdout)["roles"]
        assert roles["stop"]["name"] == "/stop" and roles["status"]["name"] == "/robot_status"
        gateway, store = gateway_on(tmp_path, ros2_transport="cli")
        try:
            assert until(lambda: gateway.state().status is not None, 15), "no /robot_status"
            result, _ = ask(gateway, "where is the robot?")
            msg = gateway.run(f"ros2 topic echo {roles['pose']['name']} --once").values
            x = msg["x"] if "x" in msg else msg["pose"]["pose"]["position"]["x"]
            assert f"x {x:.2f} m" in result.answer, result.answer
            # ros2 topic bw through the CLI: the bytes DDS carried, as the verb's module says
            from astiop.ros2.cdr import serialized_size

            scan = gateway.run("ros2 topic echo /scan --once").values
            bw = gateway.run("ros2 topic bw /scan", timeout=15)
            assert bw.executed and not bw.error and bw.values["reports"] >= 2, bw.error
            size = serialized_size("sensor_msgs/msg/LaserScan", scan)
            assert f"Message size mean: {size / 1000:.2f} KB" in bw.output, (size, bw.output)
            found = gateway.run("ros2 topic find sensor_msgs/msg/LaserScan")  # the graph's
            assert found.executed and found.output == "/scan\n", (found.error, found.output)
        finally:
            gateway.close()
            store.close()
        out = astiop_cli(tmp_path, "estop")
        assert out.returncode == 0, out.stdout + out.stderr
        assert ["service", "call", "/stop", "std_srvs/srv/Trigger", "{}"] in ros2_calls(folder)
