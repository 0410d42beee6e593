"""The ros2 path end to end: astiop's ros2 backend, real subprocesses, and an emulated robot in
its own process whose `ros2` parses arguments as ros2cli does."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.store import Store
from tests.emulator import (
    ARMED_ESTOP,
    cmd_vel_received,
    emulated_robot,
    on_path,
    ros2_calls,
    ros2_log,
)

YES = lambda _c: True  # noqa: E731
GOAL = (
    "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
    '"{pose: {header: {frame_id: map}, pose: {position: {x: 6.0, y: 3.0}}}}"'
)


def until(predicate, timeout: float = 30.0) -> bool:  # returns as soon as it holds
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return False


def idle(gateway) -> bool:
    st = gateway.state()
    return st.pose is not None and st.status is not None and st.status.state == "idle"


pytestmark = pytest.mark.slow  # each test starts a robot process


@pytest.fixture
def robot(monkeypatch):
    with emulated_robot(speed=4.0) as folder:  # motion 4x real time: tests wait less
        on_path(monkeypatch, folder)
        yield folder


def make_gateway(store: Store | None = None, *, stream: bool = True) -> RobotGateway:
    from astiop.transports.ros2cli.backend import Ros2Backend

    gateway = RobotGateway(Ros2Backend("ros2", 10.0, stream=stream), SafetyPolicy(), store=store)
    gateway.start()
    return gateway


def test_live_state_comes_from_echo_streams(robot):
    gateway = make_gateway()
    try:

        def complete() -> bool:  # each topic has its own stream: wait for all it reads
            st = gateway.state()
            return None not in (st.battery, st.scan, st.status, st.pose)

        assert until(complete)
        st = gateway.state()
        assert st.status.state == "charging" and st.pose.x == pytest.approx(1.15, abs=0.05)
        assert 0.0 < st.battery.percentage <= 1.0
        assert len(st.scan.ranges) == 360  # echoed in full, not ros2's 128
        assert until(lambda: gateway.map_geometry() is not None)
        assert gateway.map_geometry().bounds == pytest.approx((0.0, 0.0, 40.0, 25.0))
        echoes = [c for c in ros2_calls(robot) if c[:2] == ["topic", "echo"]]
        streams = [c for c in echoes if "--once" not in c]
        assert len(streams) == len({c[2] for c in streams})  # one process per topic
    finally:
        gateway.close()


def test_what_is_sent_is_rebuilt_and_clamped(robot):
    gateway = make_gateway(stream=False)
    try:
        gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
        r = gateway.run(
            "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'x; rm -rf /'}\"",
            confirm=YES,
        )
        assert r.executed and r.values["success"] is False  # the robot knows no such place
        r = gateway.run(
            "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 5.0}}'",
            confirm=YES,
        )
        assert r.executed and not r.error, r.error
        assert not gateway.run("ros2 service call /warp std_srvs/srv/Trigger", confirm=YES).executed
    finally:
        gateway.close()
    calls = ros2_calls(robot)
    goto = next(c for c in calls if c[:3] == ["service", "call", "/goto_position"])
    assert goto[3] == "astiop_msgs/srv/GotoPosition"  # the type is always sent
    assert ARMED_ESTOP in calls  # the E-STOP's publisher, armed ahead of time
    pub = next(c for c in calls if c[:3] == ["topic", "pub", "--once"])
    assert "x: 0.8" in pub[-1]  # the clamped message went out, not the typed one
    assert not any("/warp" in c for c in calls)  # a rejected command never runs
    assert cmd_vel_received(robot)[-1]["twist"]["linear"]["x"] == pytest.approx(0.8)


def test_goal_returns_at_acceptance_and_stop_cancels_it(robot):
    gateway = make_gateway()
    try:
        gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
        assert until(lambda: idle(gateway))
        r = gateway.run(GOAL, confirm=YES)
        assert r.values["accepted"]
        procs = gateway.backend._commands.goal_procs
        assert any(p.poll() is None for p in procs)  # returned at acceptance
        assert until(lambda: gateway.state().status.state == "navigating")
        gateway.run("ros2 service call /stop std_srvs/srv/Trigger")
        assert gateway.wait_until_idle(15) == "canceled"
    finally:
        gateway.close()


def test_estop_sends_zero_twist_even_without_a_stop_service(monkeypatch):
    with emulated_robot(latency_ms=300, missing=("/stop",)) as folder:
        on_path(monkeypatch, folder)
        gateway = make_gateway(stream=False)
        try:
            # the armed publisher has started (under CI's load that took more than 0.6 s)
            assert until(lambda: ARMED_ESTOP in ros2_calls(folder))
            pressed = time.monotonic()
            assert gateway.estop() == []  # a robot with no stop service: said, not failed
            said = [e.message for e in gateway.events_since(0) if e.kind == "estop"]
            assert any("no stop service (/stop)" in m for m in said), said
            assert until(lambda: cmd_vel_received(folder))
            first = cmd_vel_received(folder)[0]
            assert first["twist"]["linear"]["x"] == 0.0
            # no ros2 call was started for it: the publisher armed before the press sent it
            pubs = [e for e in ros2_log(folder) if e["argv"][:2] == ["topic", "pub"]]
            assert pubs and all(e["mono"] < pressed for e in pubs)
            assert first["mono"] >= pressed
            r = gateway.run(GOAL, confirm=YES)
            assert not r.executed and "E-STOP" in r.reason
        finally:
            gateway.close()
        assert not any(c[:2] == ["action", "send_goal"] for c in ros2_calls(folder))


def test_astiop_estop_ends_after_its_zero_twists_and_stop_went_out(monkeypatch, tmp_path):
    with emulated_robot(latency_ms=300) as folder:
        on_path(monkeypatch, folder)
        cli = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "e.db"), "--robot", "ros2"]
        out = subprocess.run([*cli, "estop"], capture_output=True, text=True, timeout=60)
        ended = time.monotonic()
        assert out.returncode == 0 and "E-STOP engaged and latched" in out.stdout, out.stderr
        # the `topic pub -t 10` ran to its end before the command said so (not left behind)
        zeros = [t for t in cmd_vel_received(folder) if t["twist"]["linear"]["x"] == 0.0]
        assert len(zeros) == 10 and zeros[-1]["mono"] < ended, zeros
        # no graph read first (10-25 s with the real CLI): /cmd_vel's type, then the pub
        # (and, alongside, the services listed: a Nav2 robot's cancel_goal, in case no /stop)
        calls = [c[:3] for c in ros2_calls(folder)]
        listing = ["service", "list", "-t"]
        acts = [c for c in calls if c != listing]
        first = [["service", "call", "/stop"], ["topic", "type", "/cmd_vel"]]
        assert sorted(acts[:2]) == first and acts[2] == ["topic", "pub", "-r"], calls
        assert listing in calls[:3], calls
        # again, the E-STOP latched already: each step goes out once, not once more for the latch
        out = subprocess.run([*cli, "estop"], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        again = [c[:3] for c in ros2_calls(folder)[len(calls) :] if c[:3] != listing]
        assert sorted(again) == sorted(acts), ros2_calls(folder)


def test_astiop_estop_on_a_robot_without_stop_says_so_and_still_zeroes_cmd_vel(
    monkeypatch, tmp_path
):
    with emulated_robot(missing=("/stop",), daemon_stopped=True) as folder:
        on_path(monkeypatch, folder)
        monkeypatch.setenv("ASTIOP_ROBOT__ROS2_TIMEOUT_S", "2")
        cli = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "e.db"), "--robot", "ros2"]
        out = subprocess.run([*cli, "estop"], capture_output=True, text=True, timeout=60)
        assert out.returncode == 1 and "latched (with failures above)" in out.stdout
        assert "E-STOP /stop: nothing answered it in 2 s" in out.stderr, out.stderr
        zeros = [t for t in cmd_vel_received(folder) if t["twist"]["linear"]["x"] == 0.0]
        assert len(zeros) == 10, zeros


def test_teleop_holds_one_publisher_and_lapses(robot):
    gateway = make_gateway()
    try:
        gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
        assert until(lambda: idle(gateway))
        x0 = gateway.state().pose.x
        for _ in range(15):
            r = gateway.drive(-0.4, 0.0, 0.0)  # it faces west after undocking: +x
            assert r.executed, r.reason
            time.sleep(0.1)
        assert until(lambda: gateway.state().pose.x > x0 + 0.2)
        pubs = [c for c in ros2_calls(robot) if c[:4] == ["topic", "pub", "-r", "10"]]
        assert len(pubs) == 1  # one long-lived publisher, not a process per key
        assert until(lambda: cmd_vel_received(robot)[-1]["twist"]["linear"]["x"] == 0.0)
    finally:
        gateway.close()


def test_estop_in_one_process_holds_another(robot, tmp_path):
    store = Store(tmp_path / "shared.db")
    gateway = make_gateway(store, stream=False)
    gateway.estop()
    gateway.close()
    cmd = [
        sys.executable,
        "-m",
        "astiop",
        "--db",
        str(tmp_path / "shared.db"),
        "--robot",
        "ros2",
        "exec",
        "--yes",
        "ros2 service call /dock std_srvs/srv/Trigger",
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "E-STOP" in out.stderr
    assert not any(c[:3] == ["service", "call", "/dock"] for c in ros2_calls(robot))
    restarted = make_gateway(Store(tmp_path / "shared.db"), stream=False)
    try:
        assert restarted.e_stopped  # a restart keeps it until it is released
    finally:
        restarted.close()


def test_a_stream_that_dies_is_restarted_and_said_so(robot):
    gateway = make_gateway()
    try:
        stream = gateway.backend._streams["/battery_status"]
        assert until(lambda: stream.count >= 1)
        stream._proc.kill()
        count = stream.count
        assert until(lambda: stream.restarts == 1 and stream.count > count, 15)
        events = gateway.events_since(0)
        assert any(e.kind == "stream" and "/battery_status" in e.message for e in events)
    finally:
        gateway.close()


def test_a_refusal_printed_with_status_0_is_an_error(robot):
    from astiop.transports.ros2cli.backend import Ros2Backend

    gateway = make_gateway(stream=False)
    try:
        r = gateway.run("ros2 param set /astibot_base max_linear_speed 1", confirm=YES)
        assert r.executed and not r.error  # astiop sends 1.0 for a double parameter
        assert ["param", "set", "/astibot_base", "max_linear_speed", "1.0"] in ros2_calls(robot)
        backend: Ros2Backend = gateway.backend
        out = backend._run(["param", "set", "/astibot_base", "max_linear_speed", "1"], 10.0)
        assert out.returncode == 0 and "Setting parameter failed" in out.out  # as rclcpp does
    finally:
        gateway.close()


def test_a_service_nobody_serves_is_reported_within_its_bound(monkeypatch):
    with emulated_robot(missing=("/dock",)) as folder:
        on_path(monkeypatch, folder)
        from astiop.ros2.catalog import astibot_catalog
        from astiop.transports.ros2cli.backend import Ros2Backend

        backend = Ros2Backend("ros2", 10.0, stream=False)
        backend.catalog.services["/dock"] = astibot_catalog().services["/dock"]  # listed earlier
        gateway = RobotGateway(backend, SafetyPolicy())
        t0 = time.monotonic()
        r = gateway.run("ros2 service call /dock std_srvs/srv/Trigger", confirm=YES, timeout=2.0)
        assert "service /dock is not available" in r.error
        assert time.monotonic() - t0 < 30  # not forever: the bound holds
        gateway.close()


def test_the_graph_is_read_from_the_robot_and_refreshed_when_a_name_is_missing(robot):
    gateway = make_gateway(stream=False)
    try:
        backend = gateway.backend
        assert "/navigator" in backend.catalog.nodes and "/map" in backend.catalog.topics
        assert ["daemon", "start"] in ros2_calls(robot)
        del backend.catalog.topics["/battery_status"]  # as if it appeared after the last read
        backend.refreshed_at = 0.0
        r = gateway.run("ros2 topic echo /battery_status --once")
        assert r.executed and not r.error and 0 < r.values["percentage"] <= 1
    finally:
        gateway.close()


def test_a_fresh_daemon_is_read_until_the_graph_settles_a_running_one_once(monkeypatch):
    def rounds(folder) -> int:
        return sum(c == ["topic", "list", "-t"] for c in ros2_calls(folder))

    def status() -> str:
        return subprocess.run(["ros2", "daemon", "status"], capture_output=True, text=True).stdout

    with emulated_robot(daemon_stopped=True) as folder:
        on_path(monkeypatch, folder)
        assert status() == "The daemon is not running\n"
        subprocess.run(["ros2", "interface", "show", "std_srvs/srv/Trigger"], capture_output=True)
        assert status() == "The daemon is not running\n"  # no NodeStrategy: no daemon
        make_gateway(stream=False).close()  # started the daemon: discovery may still be under way
        assert rounds(folder) == 2
        make_gateway(stream=False).close()  # a second console finds it running
        assert rounds(folder) == 3


def test_byte_fields_printed_as_characters_are_read_as_numbers(robot):
    gateway = make_gateway(stream=False)
    try:
        r = gateway.run("ros2 topic echo /diagnostics --once")
        assert r.executed and not r.error, r.error
        levels = [s["level"] for s in r.values["status"]]
        assert levels and all(isinstance(level, int) for level in levels)
        echoed = gateway.backend._run(["topic", "echo", "/diagnostics", "--once"], 10.0).out
        assert 'level: "\\0"' in echoed or 'level: "\\x00"' in echoed  # what ros2 printed
    finally:
        gateway.close()


def test_hz_returns_after_two_windows_with_the_rate(monkeypatch):
    with emulated_robot() as folder:  # real time: the rate is measured on the wall clock
        on_path(monkeypatch, folder)
        gateway = make_gateway(stream=False)
        try:
            r = gateway.run("ros2 topic hz /robot_pose", timeout=15)
            # stopped once two windows were read, not at the bound (on a loaded machine a third
            # may be printed before the process is stopped: what it printed is reported)
            assert 2 <= r.values["windows"] <= 3 and r.duration_s < 10, (r.values, r.duration_s)
            assert 5.0 < r.values["average_rate"] < 15.0  # /robot_pose is 10 Hz
        finally:
            gateway.close()


def test_a_goal_with_feedback_is_followed_to_its_result(robot):
    gateway = make_gateway()
    try:
        gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
        assert until(lambda: idle(gateway))
        near = GOAL.replace("x: 6.0", "x: 3.0") + " --feedback"
        r = gateway.run(near, confirm=YES)
        assert r.values["accepted"]
        assert gateway.wait_until_idle(60) == "succeeded"
        pose = gateway.state().pose
        assert abs(pose.x - 3.0) < 0.3 and abs(pose.y - 3.0) < 0.3  # it got there
        assert any(e.kind == "goal" and "SUCCEEDED" in e.message for e in gateway.events_since(0))
    finally:
        gateway.close()


def test_the_emulated_robot_holds_after_stop_until_release(robot):
    """Driven with its own `ros2`, as any client would: after /stop the base ignores /cmd_vel
    and refuses goals, read from its own /odom and /robot_status; /release lets it move."""
    import yaml

    def ros2(*argv: str) -> str:
        out = subprocess.run(["ros2", *argv], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        return out.stdout

    def echo(topic: str) -> dict:
        return yaml.safe_load(ros2("topic", "echo", topic, "--once").split("---")[0])

    def back_up() -> None:  # it faces west after undocking: backwards is +x
        ros2("topic", "pub", "-t", "15", "-r", "10", "/cmd_vel", "geometry_msgs/msg/Twist",
             "{linear: {x: -0.3}}")  # fmt: skip

    trigger = ("std_srvs/srv/Trigger",)
    assert "/release" in ros2("service", "list").split()
    ros2("service", "call", "/undock", *trigger)
    assert until(lambda: echo("/robot_status")["state"] == "idle", 60)
    assert "success=True" in ros2("service", "call", "/stop", *trigger)
    rest = echo("/odom")["pose"]["pose"]["position"]
    back_up()
    odom = echo("/odom")
    assert odom["twist"]["twist"]["linear"]["x"] == 0.0
    assert abs(odom["pose"]["pose"]["position"]["x"] - rest["x"]) < 1e-3
    assert cmd_vel_received(robot), "the Twists arrived; the base ignored them"
    goal = ros2(
        "service", "call", "/goto_position", "astiop_msgs/srv/GotoPosition", "{x: 6.0, y: 3.0}"
    )
    assert "success=False" in goal and "latched" in goal
    assert echo("/robot_status")["state"] == "e_stopped"
    assert "success=True" in ros2("service", "call", "/release", *trigger)
    back_up()
    assert echo("/odom")["pose"]["pose"]["position"]["x"] > rest["x"] + 0.2


def test_the_emulated_ros2_refuses_what_real_ros2_refuses(robot):
    def ros2(*argv: str) -> subprocess.CompletedProcess:
        return subprocess.run(["ros2", *argv], capture_output=True, text=True, timeout=20)

    bad_type = ros2("topic", "echo", "/battery_status", "-1")
    assert bad_type.returncode == 1 and "message type is invalid" in bad_type.stderr
    exclusive = ros2("topic", "pub", "--once", "-t", "5", "/cmd_vel", "geometry_msgs/msg/Twist")
    assert exclusive.returncode == 2 and "not allowed with argument" in exclusive.stderr
    no_type = ros2("service", "call", "/stop")
    assert no_type.returncode == 2 and "service_type" in no_type.stderr


async def test_a_turn_on_the_robot_says_started_then_follows_up_arrived(robot, store):
    """A service goal reports no outcome on a real robot: the follow-up reads the robot's
    own pose at the target, and the gate and grounding work on the live graph."""
    from astiop.agent.models.specs import open_endpoint
    from astiop.agent.turn import Agent

    gateway = make_gateway()
    try:
        gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
        assert until(lambda: idle(gateway))
        agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES)
        result = await agent.turn("go to x 4, y 3")
        assert result.started.startswith("goal accepted: (4, 3)") and "arriv" not in result.answer
        follow = await agent.follow_up(result, timeout_s=60)
        assert follow.startswith("arrived: (4, 3)") and result.outcome == "succeeded"
        refused = await agent.turn("is anything blocking it? then dock")
        assert not refused.refused  # a question and a dock: both asked
        wrong = agent.gate_reason("where is it?", ["ros2 service call /dock std_srvs/srv/Trigger"])
        assert wrong and "question" in wrong
    finally:
        gateway.close()


def test_parameters_are_read_from_the_robot_with_their_types(robot):
    gateway = make_gateway(stream=False)
    try:
        params = gateway.catalog.params
        assert params[("/astibot_base", "max_linear_speed")].type == "double"
        assert params[("/astibot_base", "max_linear_speed")].writable  # astiop knows its limits
        sim_time = params[("/navigator", "use_sim_time")]  # on the robot, not in astiop's table
        assert sim_time.type == "boolean" and not sim_time.writable
        r = gateway.run("ros2 param get /navigator use_sim_time")
        assert r.executed and not r.error and "Boolean value is: False" in r.output
        refused = gateway.run("ros2 param set /navigator use_sim_time true", confirm=YES)
        assert not refused.executed and "read-only" in refused.reason
        assert ["param", "list", "--param-type"] in ros2_calls(robot)
    finally:
        gateway.close()


def test_echo_text_is_what_ros2_prints_with_the_same_options(robot):
    gateway = make_gateway(stream=False)
    try:
        argv = ["topic", "echo", "/battery_status", "--once", "-l", "3", "--no-arr"]
        ours = gateway.run("ros2 " + " ".join(argv)).output
        theirs = subprocess.run(
            [str(robot / "ros2"), *argv], capture_output=True, text=True, timeout=30
        ).stdout
        keep = ("location:", "serial_number:", "cell_voltage:", "power_supply_technology:")
        assert [ln for ln in ours.splitlines() if ln.startswith(keep)] == [
            ln for ln in theirs.splitlines() if ln.startswith(keep)
        ]
        assert "location: 2x ..." in ours
    finally:
        gateway.close()


def test_display_options_shape_the_text_but_the_values_stay_whole(robot):
    gateway = make_gateway(stream=False)
    try:
        status = gateway.run("ros2 topic echo /robot_status --once --no-str")
        assert status.values["state"] in ("idle", "charging") and "<string length" in status.output
        scan = gateway.run("ros2 topic echo /scan --once --no-arr -l 5")
        assert len(scan.values["ranges"]) == 360 and "<sequence type" in scan.output
        sent = [c for c in ros2_calls(robot) if c[:3] == ["topic", "echo", "/scan"]]
        assert sent and "--no-arr" not in sent[-1] and "-l" not in sent[-1]
    finally:
        gateway.close()


def test_param_and_interface_lists_print_as_ros2cli_on_the_emulated_and_in_process_robots(robot):
    """One printing for both (ros2/printing.py): the node's header only when no node is named,
    --param-type, --filter (re.match), --param-prefixes (the name or under it), -s."""
    from astiop.config import load_settings
    from astiop.robot.factory import make_sim_gateway

    gateway = make_gateway(stream=False)
    cfg = load_settings({}, env={}, path=robot / "none.toml")
    sim = make_sim_gateway(cfg, Store(robot / "sim.db"), realtime=False)
    try:
        for command, expected in (
            ("ros2 param list /navigator", "  goal_tolerance\n  inflation_radius\n"),
            ("ros2 param list /astibot_base --param-type", "  max_angular_speed (type: double)\n"),
            ("ros2 param list --filter 'max_l.*'", "/astibot_base:\n  max_linear_speed\n"),
            ("ros2 param list --param-prefixes max", ""),
            (
                "ros2 interface list -s",
                "Services:\n    action_msgs/srv/CancelGoal\n    astiop_msgs/srv/GotoPosition\n",
            ),
        ):
            for where, gw in (("emulated ros2", gateway), ("in process", sim)):
                r = gw.run(command)
                assert r.executed and not r.error, (where, command, r.error)
                assert r.output.startswith(expected), (where, command, r.output)
        refused = sim.run("ros2 param list --filter 'max_('")
        assert not refused.executed and "--filter is not a regular expression" in refused.reason
    finally:
        gateway.close()
        sim.close()
