"""A robot astiop did not write, operated as the ASTIbot is: a TurtleBot3 under Nav2 on Jazzy
(`astiop sim node --robot turtlebot3`: upstream's names and types), over real DDS through rclpy,
with no profile file. Its roles are found on its graph; questions are answered with what it
published (its map pose from /amcl_pose, its 0-100 battery, its scan); a goal by coordinates
goes out as a NavigateToPose and arrives; teleop drives it in its own velocity type; the E-STOP
stops it with no /stop service by cancelling every Nav2 goal on it, another client's too; and the
same under a namespace. And a robot with its battery missing answers the battery question so."""

from __future__ import annotations

import asyncio
import json
import math
import subprocess
import sys
import time

import pytest

from astiop.config import load_settings
from astiop.robot.factory import make_robot_gateway
from astiop.store import Store
from tests.ros import battery_answer_agrees, require_ros, ros_client, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]
YES = lambda _c: True  # noqa: E731


def settings(tmp_path, **robot):
    robot = {"backend": "ros2", "ros2_transport": "rclpy", **robot}
    return load_settings(
        {"llm": {"model": "rules"}, "robot": robot}, env={}, path=tmp_path / "none.toml"
    )


def gateway_on(tmp_path, **robot):
    store = Store(tmp_path / "tb3.db")
    gateway = make_robot_gateway(settings(tmp_path, **robot), store)
    gateway.start()
    assert until(lambda: gateway.state().pose and gateway.state().battery, 30), gateway.profile
    return gateway, store


def ask(gateway, text: str):
    from astiop.agent.models.specs import open_endpoint
    from astiop.agent.turn import Agent

    agent = Agent(gateway, open_endpoint("rules"), gateway.store, confirm=YES)

    async def turn():
        result = await agent.turn(text, lambda *_: None)
        follow = await agent.follow_up(result, 90) if result.started else ""
        return result, follow

    return asyncio.run(turn())


def test_a_turtlebot3_is_read_answered_driven_and_sent_by_its_own_names(tmp_path):
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=8.0):
        gateway, store = gateway_on(tmp_path)
        try:
            profile = gateway.profile
            roles = {r: profile.name(r) for r in ("pose", "battery", "scan", "map")}
            assert roles == {"pose": "/amcl_pose", "battery": "/battery_state",
                             "scan": "/scan", "map": "/map"}  # fmt: skip
            assert profile.name("velocity_command") == "/cmd_vel"
            assert profile.matches["velocity_command"].type == "geometry_msgs/msg/TwistStamped"
            assert profile.name("navigation") == "/navigate_to_pose"
            assert profile.make == "turtlebot3_burger" and not profile.has("stop")
            # a client this process keeps (an E-STOP's call, tried) is not a service it has
            from std_srvs.srv import Trigger

            gateway.backend.proc.client(Trigger, "/stop")
            gateway.backend.refresh()
            assert not gateway.profile.has("stop"), gateway.catalog.services.keys()
            # the Dashboard's figures: the map pose (not odometry's origin), the battery, the map
            st = gateway.state()
            assert math.dist((st.pose.x, st.pose.y), (4.0, 4.0)) < 0.05, st.pose
            assert 0.0 < st.battery.percentage <= 1.0 and gateway.map_geometry() is not None
            # its places are its map's (the warehouse's six are not offered); its geofence, the
            # extent of its own /map
            assert store.map_name == "turtlebot3_burger" and store.list_locations() == []
            assert gateway.safety.geofence == gateway.map_geometry().bounds
            assert until(lambda: gateway.state().state_word == "idle", 10)

            result, _ = ask(gateway, "where is the robot?")
            echo = gateway.run("ros2 topic echo /amcl_pose --once").values["pose"]["pose"]
            assert f"x {echo['position']['x']:.2f} m" in result.answer, result.answer
            battery_answer_agrees(
                gateway, lambda: ask(gateway, "what is the battery level?")[0].answer
            )
            result, _ = ask(gateway, "is anything in front of the robot?")
            assert "nearest return 0.00" not in result.answer, result.answer
            assert "scan" in result.answer, result.answer

            # teleop: its own velocity type, and it moves
            for _ in range(10):
                gateway.drive(0.15, 0.0, 0.0)
                time.sleep(0.1)
            assert until(lambda: (gateway.state().speed or 0.0) > 0.05, 5), gateway.state()
            assert until(
                lambda: gateway.state().speed == 0.0 or (gateway.state().speed or 1) < 0.01, 10
            )

            # a goal by coordinates: a NavigateToPose goal, followed to its arrival
            start = gateway.state().pose
            target = (start.x + 1.2, start.y + 0.3)
            result, follow = ask(gateway, f"go to x {target[0]:.2f} y {target[1]:.2f}")
            assert result.commands[0].command.startswith(
                "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose"
            ), result.commands
            assert result.started.startswith("goal accepted"), result.answer
            # arrived as astiop holds it: Nav2's SUCCEEDED and the robot's map pose at the goal
            assert "succeeded" in follow or follow.startswith("arrived"), follow

            # "save this spot": no /save_location on it, so astiop keeps its read pose
            result, _ = ask(gateway, "save this spot as bench")
            assert result.answer.startswith("Saved 'bench' at x"), result.answer
            bench = store.get_location("bench")
            assert math.dist((bench.x, bench.y), target) < 1.0
            result, follow = ask(gateway, f"go to x {start.x:.2f} y {start.y:.2f}")
            assert "succeeded" in follow or follow.startswith("arrived"), follow
            result, follow = ask(gateway, "go to bench")
            assert f"x: {bench.x:.3f}" in result.commands[0].command, result.commands
            assert "succeeded" in follow or follow.startswith("arrived"), follow
        finally:
            gateway.close()
            store.close()


def test_a_turtlebot3_session_is_recorded_and_replayed_by_its_own_roles(tmp_path):
    """Its /amcl_pose, /tf and battery recorded with their schemas, and the replay reads them by
    the roles found on the recording (not the ASTIbot's /robot_pose)."""
    require_ros()
    from astiop.recording import SessionRecorder
    from astiop.transports.replay.backend import open_replay
    from tests.ros import tb3_node

    with tb3_node(speed=8.0):
        gateway, store = gateway_on(tmp_path)
        path = tmp_path / "tb3.mcap"
        try:
            recorder = SessionRecorder(path, gateway, store, flush_s=0.0)
            for _ in range(20):
                gateway.drive(0.2, 0.0, 0.0)
                recorder.poll()
                time.sleep(0.1)
            assert until(
                lambda: gateway.state().speed is not None and gateway.state().speed < 0.01, 10
            )
            time.sleep(0.5)
            recorder.poll()
            live = gateway.state()
            recorder.stop()
        finally:
            gateway.close()
            store.close()
    replay = open_replay(path, paused=True)
    assert replay.catalog.profile.name("pose") == "/amcl_pose"
    assert "/tf" in replay.recording.channels and "/amcl_pose" in replay.recording.channels
    replay.playback.seek(replay.recording.duration_s)
    st = replay.state()
    assert math.dist((st.pose.x, st.pose.y), (live.pose.x, live.pose.y)) < 0.05, (st, live)
    assert abs(st.battery.percentage - live.battery.percentage) < 0.01
    assert st.pose.x > 4.2  # it drove from (4, 4): the map pose, not odometry's origin


def test_the_estop_cancels_every_nav2_goal_on_a_robot_with_no_stop_service(tmp_path):
    require_ros()
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from nav_msgs.msg import Odometry
    from rclpy.action import ActionClient

    from tests.ros import tb3_node

    with tb3_node(speed=4.0), ros_client("someone_else") as client:
        odom = client.collect(Odometry, "/odom")
        action = ActionClient(client.node, NavigateToPose, "/navigate_to_pose")
        assert action.wait_for_server(timeout_sec=15)
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        # 24 m ahead (~27 s at 4x): a cold `astiop estop` on a loaded machine lands first
        goal.pose.pose.position.x, goal.pose.pose.position.y = 28.0, 4.0
        goal.pose.pose.orientation.w = 1.0
        handle = client.result(action.send_goal_async(goal))
        assert handle.accepted
        assert until(lambda: odom and abs(odom[-1][1].twist.twist.linear.x) > 0.05, 15)
        db = str(tmp_path / "estop.db")
        cli = [sys.executable, "-m", "astiop", "--db", db, "--robot", "ros2"]
        out = subprocess.run([*cli, "--ros2-transport", "rclpy", "estop"],
                             capture_output=True, text=True, timeout=60)  # fmt: skip
        # 0: no failure said, so it did not wait out its timeout for a /stop it lacks
        assert out.returncode == 0, out.stdout + out.stderr
        result = client.result(handle.get_result_async(), 20)
        assert result.status == GoalStatus.STATUS_CANCELED, result.status  # not SUCCEEDED
        assert until(lambda: abs(odom[-1][1].twist.twist.linear.x) < 0.01, 5)
        stopped = time.monotonic()
        time.sleep(1.5)
        assert all(abs(m.twist.twist.linear.x) < 0.01 for t, m in odom if t > stopped)


def test_stop_the_robot_in_chat_cancels_a_nav2_goal_and_says_so(tmp_path):
    """A zero Twist alone does not stop a Nav2 robot (its controller drives on): "stop the
    robot" cancels every goal of its NavigateToPose server, then holds it still."""
    require_ros()
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from nav_msgs.msg import Odometry
    from rclpy.action import ActionClient

    from tests.ros import tb3_node

    with tb3_node(speed=4.0), ros_client("someone_else") as client:
        gateway, store = gateway_on(tmp_path)
        try:
            odom = client.collect(Odometry, "/odom")
            action = ActionClient(client.node, NavigateToPose, "/navigate_to_pose")
            assert action.wait_for_server(timeout_sec=15)
            goal = NavigateToPose.Goal()
            goal.pose.header.frame_id = "map"
            # 24 m ahead: it ends only when stopped, however loaded the machine
            goal.pose.pose.position.x, goal.pose.pose.position.y = 28.0, 4.0
            goal.pose.pose.orientation.w = 1.0
            handle = client.result(action.send_goal_async(goal))
            assert handle.accepted
            assert until(lambda: odom and abs(odom[-1][1].twist.twist.linear.x) > 0.05, 15)
            result, _ = ask(gateway, "stop the robot")
            cancel, zero = (c.command for c in result.commands)
            assert cancel.startswith("ros2 service call /navigate_to_pose/_action/cancel_goal")
            assert zero.startswith("ros2 topic pub --once /cmd_vel")
            ran = [(c.command[:40], c.executed, c.error) for c in result.commands]
            assert all(c.executed and not c.error for c in result.commands), ran
            assert "cancel" in result.answer.lower(), result.answer
            done = client.result(handle.get_result_async(), 20)
            assert done.status == GoalStatus.STATUS_CANCELED, done.status  # not SUCCEEDED
            assert until(lambda: abs(odom[-1][1].twist.twist.linear.x) < 0.01, 5)
        finally:
            gateway.close()
            store.close()


def test_a_turtlebot3_under_a_namespace_is_found_and_stopped_there(tmp_path):
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=8.0, namespace="/tb3_1"):
        db = str(tmp_path / "ns.db")
        cli = [sys.executable, "-m", "astiop", "--db", db, "--robot", "ros2"]
        cli += ["--ros2-transport", "rclpy", "--namespace", "/tb3_1"]
        out = subprocess.run([*cli, "robot", "profile", "--json"], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        profile = json.loads(out.stdout)
        assert profile["namespace"] == "/tb3_1"
        assert profile["roles"]["battery"]["name"] == "/tb3_1/battery_state"
        assert profile["roles"]["velocity_command"]["name"] == "/tb3_1/cmd_vel"
        assert profile["roles"]["navigation"]["name"] == "/tb3_1/navigate_to_pose"
        # a one-shot command reads the robot's /map for the geofence (its watch never started)
        far = ("ros2 action send_goal /tb3_1/navigate_to_pose nav2_msgs/action/NavigateToPose "
               "'{pose: {header: {frame_id: map}, pose: {position: {x: 60.0, y: 4.0}}}}'")  # fmt: skip
        out = subprocess.run([*cli, "exec", far, "--yes"], capture_output=True, text=True)
        assert (
            out.returncode != 0 and "outside the geofence (x 0.5..39.5" in out.stdout + out.stderr
        )
        out = subprocess.run([*cli, "estop"], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stdout + out.stderr
        assert "no /cmd_vel" not in out.stderr


def test_a_robot_with_no_battery_reading_says_so_when_asked(monkeypatch, tmp_path):
    """The emulated ASTIbot without /battery_status, on the CLI transport: not "the robot is
    charging" read off its status instead."""
    from tests.emulator import emulated_robot, on_path
    from tests.ros.test_ros2_emulated import make_gateway

    with emulated_robot(missing=("/battery_status",)) as folder:
        on_path(monkeypatch, folder)
        store = Store(tmp_path / "nobattery.db")
        gateway = make_gateway(store)
        try:
            assert gateway.profile.name("battery") is None
            result, _ = ask(gateway, "what is the battery level?")
            assert result.answer.startswith("This robot publishes no battery state"), result.answer
            assert "charging" not in result.answer and not result.commands
            result, _ = ask(gateway, "where is the robot?")
            assert "x " in result.answer, result.answer  # what it does publish is still read
        finally:
            gateway.close()
            store.close()
        # `astiop chat` prints an answer given without the model (it came whole, not streamed)
        cli = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "cli.db"), "--robot",
               "ros2", "--ros2-transport", "cli", "chat", "-m", "rules"]  # fmt: skip
        with emulated_robot(missing=("/battery_status",)) as folder:
            on_path(monkeypatch, folder)
            out = subprocess.run([*cli, "what is the battery level?"], capture_output=True,
                                 text=True, timeout=120)  # fmt: skip
        assert out.returncode == 0, out.stderr[-2000:]
        assert out.stdout.startswith("This robot publishes no battery state"), out.stdout


TB3_SUITE = """\
name: tb3-check
stage: 2
system: You operate a mobile robot.
cases:
  - {id: pos, category: position, request: "Where is the robot right now?", expect: ["topic echo /robot_pose"], answer: [position]}
  - {id: bat, category: battery, request: "What is the battery level?", expect: ["topic echo /battery_status"], answer: [battery]}
  - {id: xy, category: coordinates, request: "Drive to x 6, y 4.5", expect: ["service call /goto_position x=6.0 y=4.5"], outcome: {arrive: [6.0, 4.5]}}
  - {id: bench, category: navigation, request: "Go to bench", setup: {start: [6.0, 4.5, 0.0]}, expect: ["service call /goto_position name=bench"], outcome: {arrive: bench}}
  - {id: nav, category: navigation, request: "Go to the shipping area", expect: ["service call /goto_position name=shipping"], outcome: {arrive: shipping}}
  - {id: sta, category: status, request: "What is the robot status?", expect: ["topic echo /robot_status"], answer: [state]}
  - {id: dck, category: docking, request: "Dock the robot", expect: ["service call /dock"], outcome: {docked: true}}
"""


def test_stage_2_runs_on_a_turtlebot3_in_its_own_names(tmp_path):
    """The ASTIbot's cases, carried over by role: its pose, battery and NavigateToPose goals are
    checked against what it reported; a case it has no role or place for is skipped, said why."""
    require_ros()
    from tests.ros import tb3_node

    suite = tmp_path / "tb3.yaml"
    suite.write_text(TB3_SUITE, encoding="utf-8")
    db = str(tmp_path / "bench.db")
    cli = [sys.executable, "-m", "astiop", "--db", db]
    added = subprocess.run([*cli, "locations", "--map", "turtlebot3_burger", "add", "bench", "4.5",
                            "4.0"], capture_output=True, text=True)  # fmt: skip
    assert added.returncode == 0, added.stderr
    with tb3_node(speed=8.0):
        out = subprocess.run(
            [*cli, "--robot", "ros2", "--ros2-transport", "rclpy", "bench", "run", "--stage", "2",
             "--model", "rules", "--suite", str(suite), "--json"],
            capture_output=True, text=True, timeout=600,
        )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    report = subprocess.run([*cli, "bench", "report", "1", "--format", "json"],
                            capture_output=True, text=True)  # fmt: skip
    rows = {r["case_id"]: r for r in json.loads(report.stdout)["cases"]}
    for case in ("pos", "bat", "xy", "bench"):
        r = rows[case]
        assert r["outcome"] == "ok" and r["command"] == 100.0 and r["interpretation"] == 100.0, str(
            r
        )
    assert rows["xy"]["commands"][0].startswith("ros2 action send_goal /navigate_to_pose")
    assert rows["bench"]["outcome_checks"] == {"arrive": True}
    assert rows["nav"]["outcome"] == "skipped" and "no place" in rows["nav"]["skipped"]
    assert rows["sta"]["outcome"] == "skipped" and "status" in rows["sta"]["skipped"]
    assert rows["dck"]["outcome"] == "skipped" and "dock" in rows["dck"]["skipped"]


async def test_an_outside_agent_reads_and_drives_a_turtlebot3_through_mcp(tmp_path):
    """The MCP tools by role: the state's ages by its own topics, a pose goal as a NavigateToPose
    goal, and stop as its goals cancelled, on a robot with no /stop."""
    require_ros()
    import os

    from mcp import Client, StdioServerParameters
    from mcp.types import Implementation

    from tests.ros import tb3_node

    args = ["-m", "astiop", "--db", str(tmp_path / "mcp.db"), "--robot", "ros2",
            "--ros2-transport", "rclpy", "mcp", "--approve-actuation"]  # fmt: skip
    server = StdioServerParameters(command=sys.executable, args=args, env=dict(os.environ))

    async def call(client, name, arguments=None):
        result = await client.call_tool(name, arguments or {})
        return result.is_error, "\n".join(c.text for c in result.content)

    with tb3_node(speed=4.0):
        async with Client(server, client_info=Implementation(name="pytest", version="1")) as c:
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:  # the server's robot discovered, then read
                error, text = await call(c, "robot_state")
                state = json.loads(text)
                if state["pose"] and state["battery"]:
                    break
                time.sleep(0.5)
            assert not error and 0 <= state["pose"]["age_s"] < 5, state
            assert 0 <= state["battery"]["age_s"] < 5, state
            error, text = await call(c, "read_topic", {"topic": "/battery_state"})
            assert not error and "percentage:" in text, text
            # its NavigateToPose action discovered by the server too (under load an action's
            # endpoints may come seconds after the rest; before, a goal goes on /goal_pose)
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                actions = (await call(c, "ros2_query", {"command": "ros2 action list"}))[1]
                if "/navigate_to_pose" in actions:
                    break
                time.sleep(0.5)
            assert "/navigate_to_pose" in actions, actions
            error, text = await call(c, "go_to_pose", {"x": 12.0, "y": 4.0, "theta_deg": 0.0})
            assert not error and text.startswith("goal accepted"), text
            time.sleep(2.0)
            error, text = await call(c, "stop")
            assert not error and text.startswith("its navigation goals canceled"), text
            time.sleep(1.0)
            state = json.loads((await call(c, "robot_state"))[1])
            assert "still going" not in json.dumps(state.get("last_goal")), state
            assert state["pose"]["x_m"] < 11.0, state  # stopped on its way, not arrived


def test_a_turtlebot3_answers_each_question_in_its_own_names_or_says_what_it_lacks(tmp_path):
    """The subjects on a robot astiop did not write: its battery's unset 0.0 temperature is
    said missing (never 0 °C), its heading read from /amcl_pose, its lidar's range from its own
    /scan, why it is still from its odometry (it has no status), its top speed from Nav2's
    controller parameters."""
    require_ros()
    from tests.ros import tb3_node

    with tb3_node(speed=8.0):
        gateway, _ = gateway_on(tmp_path)
        try:
            r, _ = ask(gateway, "what temperature is the battery?")
            assert "reports no battery temperature" in r.answer, r.answer
            r, _ = ask(gateway, "which way is the robot facing?")
            assert [c.command for c in r.commands] == ["ros2 topic echo /amcl_pose --once"]
            assert "faces" in r.answer
            r, _ = ask(gateway, "what is the lidar's maximum range?")
            assert f"{r.commands[0].values['range_max']:g} m" in r.answer
            r, _ = ask(gateway, "why is the robot not moving?")
            assert r.commands[0].command == "ros2 topic echo /odom --once"
            assert "reports no status" in r.answer
            r, _ = ask(gateway, "what is the robot's top speed?")  # Nav2's own parameter
            assert "/controller_server's FollowPath.max_vel_x is 0." in r.answer, r.answer
        finally:
            gateway.close()
