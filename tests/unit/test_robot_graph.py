"""The robot graph: every catalog entry, valid and invalid; nothing rejected ever runs."""

import contextlib
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.grammar import CommandSyntaxError, parse
from astiop.ros2.interfaces import interface_show
from astiop.ros2.validation import validate
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend

CAT = astibot_catalog()
YES = lambda _c: True  # noqa: E731

VALID = [
    "ros2 topic list",
    "ros2 topic list -t",
    "ros2 topic info /scan",
    "ros2 topic type /odom",
    "ros2 topic hz /scan",
    "ros2 topic echo /robot_pose --once",
    "ros2 topic echo robot_pose --once",
    "ros2 topic echo /scan --qos-reliability best_effort --once",
    "ros2 topic echo /odom nav_msgs/msg/Odometry --once",
    "ros2 topic echo /scan --once --no-arr",
    "ros2 topic echo /battery_status",
    "ros2 topic echo /robot_status --once",
    "ros2 topic echo /obstacles --once",
    "ros2 topic echo /diagnostics --once",
    "ros2 topic echo /conveyor/status --once",
    "ros2 topic echo /tf --once",
    "ros2 topic echo /tf_static --once",
    "ros2 topic echo /camera/image_raw --once --no-arr",
    "ros2 topic hz /camera/image_raw/compressed",
    "ros2 topic info /plan",
    'ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist "{linear: {x: 0.2}}"',
    "ros2 topic pub -r 10 -t 5 /cmd_vel geometry_msgs/Twist '{angular: {z: 0.3}}'",
    "ros2 service list -t",
    "ros2 service type /dock",
    "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'shipping'}\"",
    'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{x: 20.0, y: 12.25}"',
    "ros2 service call /stop std_srvs/srv/Trigger",
    "ros2 service call /release std_srvs/srv/Trigger",
    "ros2 service call /dock std_srvs/srv/Trigger",
    "ros2 service call /undock std_srvs/srv/Trigger",
    "ros2 service call /conveyor/load std_srvs/srv/Trigger '{}'",
    "ros2 service call /conveyor/unload std_srvs/srv/Trigger",
    'ros2 service call /save_location astiop_msgs/srv/SaveLocation "{name: bay_3}"',
    "ros2 service call /list_locations astiop_msgs/srv/ListLocations",
    "ros2 action list -t",
    "ros2 action info /navigate_to_pose",
    "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
    '"{pose: {header: {frame_id: map}, pose: {position: {x: 5.0, y: 12.0}}}}" --feedback',
    "ros2 node list",
    "ros2 node info /navigator",
    "ros2 interface show sensor_msgs/msg/LaserScan",
    "ros2 interface list",
    "ros2 param list",
    "ros2 param get /astibot_base max_linear_speed",
    "ros2 param set /astibot_base max_linear_speed 0.5",
]

INVALID = [
    ("", "empty"),
    ("ls -la", "start with 'ros2'"),
    ("ros2", "incomplete"),
    ("ros2 topic echo /scan | head", "shell"),
    ("ros2 topic echo /scan; rm -rf /", "shell"),
    ("ros2 topic frobnicate /scan", "not supported"),
    ("ros2 run teleop teleop", "not supported"),
    ("ros2 topic echo /batery_status", "did you mean /battery_status"),
    ("ros2 topic echo /odom sensor_msgs/msg/LaserScan", "has type nav_msgs/msg/Odometry"),
    ("ros2 topic echo /scan --qos-reliabilty best_effort", "did you mean --qos-reliability"),
    ("ros2 topic pub /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.2}}'", "--once"),
    ("ros2 topic pub --once /odom nav_msgs/msg/Odometry '{}'", "only topic you may publish"),
    ("ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: fast}}'", "number"),
    ("ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{speed: 1}'", "no field 'speed'"),
    ("ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: [}'", "not valid YAML"),
    ("ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '[1, 2]'", "mapping"),
    ("ros2 topic pub -t 1000 -r 1 /cmd_vel geometry_msgs/msg/Twist '{}'", "longer than"),
    (
        "ros2 topic pub -r abc --once /cmd_vel geometry_msgs/msg/Twist '{}'",
        "invalid positive_float value",
    ),
    ("ros2 service call /goto std_srvs/srv/Trigger", "no service /goto"),
    ("ros2 service call /goto_position std_srvs/srv/Trigger", "has type"),
    ("ros2 service call /goto_position '{place: dock}'", "needs the service type before"),
    ("ros2 service call /goto_position astiop_msgs/srv/GotoPosition '{place: 1}'", "no field"),
    ("ros2 service call /goto_position astiop_msgs/srv/GotoPosition '{x: .inf}'", "finite"),
    ("ros2 service call /dock std_srvs/srv/Trigger '{force: true}'", "no field"),
    ("ros2 action send_goal /navigate nav2_msgs/action/NavigateToPose '{}'", "no action"),
    ("ros2 node info /teleop", "no node"),
    ("ros2 interface show foo_msgs/msg/Bar", "unknown"),
    ("ros2 param get /astibot_base turbo", "no parameter"),
    ("ros2 param set /lidar_driver frequency 20", "read-only"),
    ("ros2 param set /astibot_base max_linear_speed 9", "within"),
    ("ros2 topic echo '/scan", "quoting"),
]


def test_every_catalog_entry_has_a_valid_case():
    names = {parse(c).name for c in VALID}
    assert set(CAT.topics) <= names and set(CAT.services) <= names and set(CAT.actions) <= names


@pytest.mark.parametrize("command", VALID)
def test_valid_commands(command):
    checked = validate(command, CAT)
    assert checked.valid, checked.reason


@pytest.mark.parametrize("command,why", INVALID)
def test_invalid_commands_have_a_reason(command, why):
    checked = validate(command, CAT)
    assert not checked.valid
    assert why.lower() in checked.reason.lower(), checked.reason


class RecordingBackend(SimBackend):
    def __init__(self, *a, **k):
        super().__init__(*a, **k)
        self.ran = []

    def execute(self, checked, timeout=10.0):
        self.ran.append(checked.text)
        return super().execute(checked, timeout)


@pytest.fixture
def gateway(store):
    backend = RecordingBackend(Simulator(seed=0), store)
    return RobotGateway(backend, SafetyPolicy())


@pytest.mark.parametrize("command,why", INVALID)
def test_rejected_commands_never_reach_the_backend(gateway, command, why):
    result = gateway.run(command, confirm=YES)
    assert not result.executed and result.reason and gateway.backend.ran == []


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=120))
def test_parser_never_crashes(text):
    with contextlib.suppress(CommandSyntaxError):
        parse(text)


_SHARED = RobotGateway(RecordingBackend(Simulator(seed=0, lidar_enabled=False)), SafetyPolicy())
_pieces = st.sampled_from(
    [
        "ros2",
        "topic",
        "service",
        "action",
        "echo",
        "pub",
        "call",
        "send_goal",
        "/cmd_vel",
        "/goto_position",
        "/scan",
        "--once",
        "-t",
        "-r",
        "5",
        "{x: 1}",
        "'{linear: {x: 9}}'",
        "|",
        ";",
        "rm",
        "geometry_msgs/msg/Twist",
        "std_srvs/srv/Trigger",
        "-1",
        '"',
        "{",
    ]
)


@settings(max_examples=300, deadline=None)
@given(st.lists(_pieces, max_size=8))
def test_no_rejected_command_reaches_a_backend(words):
    backend = _SHARED.backend
    backend.ran = []
    gateway = _SHARED
    text = " ".join(words)
    result = gateway.run(text, confirm=YES)
    if not result.valid or result.reason:
        assert backend.ran == []
    else:
        assert backend.ran == [text.strip()]


def test_actuating_commands_need_confirmation(gateway):
    cmd = "ros2 service call /dock std_srvs/srv/Trigger"
    assert gateway.run(cmd).reason.startswith("this command moves the robot")
    assert gateway.run(cmd, confirm=lambda c: False).reason == "not confirmed by the operator"
    assert gateway.backend.ran == []
    assert gateway.run("ros2 service call /stop std_srvs/srv/Trigger").executed  # never held


def test_echo_battery_matches_the_sim(gateway):
    result = gateway.run("ros2 topic echo /battery_status --once")
    assert result.executed and "percentage:" in result.output and result.output.endswith("---\n")
    assert result.values["percentage"] == pytest.approx(gateway.backend.sim.battery.soc, abs=1e-3)


def test_speed_clamping(gateway):
    sim = gateway.backend.sim
    sim.undock()
    sim.run_goal(60)
    r = gateway.run(
        "ros2 topic pub -r 10 -t 20 /cmd_vel geometry_msgs/msg/Twist "
        "'{linear: {x: 2.0, y: 2.0}, angular: {z: 5.0}}'",
        confirm=YES,
    )
    assert r.executed and any("clamped" in n for n in r.notes)
    twist = r.values["twist"]
    assert math.hypot(twist["linear"]["x"], twist["linear"]["y"]) == pytest.approx(0.8)
    assert twist["angular"]["z"] == pytest.approx(1.0)
    assert sim.snapshot().speed <= 0.8 + 1e-6


def test_goto_named_location_service(gateway):
    r = gateway.run(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition "
        "\"{name: 'inspection_zone_a'}\"",
        confirm=YES,
    )
    assert r.values["success"] is True
    result = gateway.backend.sim.run_goal(300)
    assert result.status == "succeeded"
    r = gateway.run(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'mars'}\"",
        confirm=YES,
    )
    assert (
        r.executed and r.values["success"] is False and "no location named" in r.values["message"]
    )


def test_geofence(gateway):
    r = gateway.run(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition '{x: 39.9, y: 3.0}'",
        confirm=YES,
    )
    assert not r.executed and "geofence" in r.reason


@pytest.mark.parametrize(
    "orientation", ["{z: 1.0e+308, w: 1.0e+308}", "{w: 0.0}", "{z: 0.5, w: 0.5}", "{w: .nan}"]
)
def test_a_goal_whose_orientation_is_not_a_unit_quaternion_is_refused(gateway, orientation):
    r = gateway.run(
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        f'"{{pose: {{pose: {{position: {{x: 15.0, y: 3.5}}, orientation: {orientation}}}}}}}"',
        confirm=YES,
    )
    assert not r.executed and gateway.backend.ran == []
    assert "unit quaternion" in r.reason or "finite" in r.reason, r.reason


def test_action_goal_with_feedback_until_arrival(gateway):
    r = gateway.run(
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        '"{pose: {header: {frame_id: map}, pose: {position: {x: 15.0, y: 3.5}, '
        'orientation: {z: 0.0, w: 1.0}}}}" --feedback',
        confirm=YES,
    )
    assert r.executed, r.reason
    assert "Goal accepted with ID" in r.output and "distance_remaining" in r.output
    assert r.output.rstrip().endswith("Goal finished with status: SUCCEEDED")
    p = r.values["final_pose"]
    assert math.hypot(p["x"] - 15.0, p["y"] - 3.5) < 0.3


def test_estop_during_navigation(gateway):
    sim = gateway.backend.sim
    gateway.run(
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"',
        confirm=YES,
    )
    sim.step(5.0)
    gateway.estop()
    held = gateway.run(
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"',
        confirm=YES,
    )
    assert not held.executed and "E-STOP" in held.reason
    pose = sim.pose
    sim.step(2.0)
    assert math.dist(pose[:2], sim.pose[:2]) < 0.02
    status = gateway.run("ros2 topic echo /robot_status --once").values
    assert status["state"] == "e_stopped" and status["e_stopped"] is True
    gateway.release_estop()
    assert gateway.run(
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"',
        confirm=YES,
    ).values["success"]


STOP = "ros2 service call /stop std_srvs/srv/Trigger"
RELEASE = "ros2 service call /release std_srvs/srv/Trigger"
BACK_UP = "ros2 topic pub -r 10 -t 10 /cmd_vel geometry_msgs/msg/Twist '{linear: {x: -0.3}}'"


def _undocked(sim) -> None:
    sim.undock()
    assert sim.run_goal(60).status == "succeeded"  # it faces west: backing up is +x


def test_stop_holds_the_robot_until_release(gateway):
    sim = gateway.backend.sim
    _undocked(sim)
    assert gateway.run(STOP).values["success"]
    rest = sim.pose
    held = gateway.run(BACK_UP, confirm=YES)
    assert held.error and "latched" in held.error and "/release" in held.error
    goal = gateway.run(
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"',
        confirm=YES,
    )
    assert goal.values["success"] is False and "latched" in goal.values["message"]
    sim.step(2.0)
    assert sim.speed() == 0.0 and math.dist(rest[:2], sim.pose[:2]) < 1e-6
    status = gateway.run("ros2 topic echo /robot_status --once").values
    assert status["state"] == "e_stopped" and status["e_stopped"] is False  # held, not E-STOP
    assert not gateway.run(RELEASE).executed, "it lets the robot move: confirmed first"
    released = gateway.run(RELEASE, confirm=YES)
    assert released.values == {"success": True, "message": "released: the robot may move again"}
    moved = gateway.run(BACK_UP, confirm=YES)
    assert moved.executed and not moved.error
    assert sim.speed() > 0.2 and sim.pose[0] > rest[0] + 0.1


def test_the_operators_release_lets_go_of_a_stop_the_store_never_latched(store):
    """The console's ctrl+r (gateway.release_estop) after a bare /stop: the robot's latch goes
    too. While the E-STOP is latched, /release itself is held like any other actuation."""
    sim = Simulator(seed=0)
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy(), store=store)
    _undocked(sim)
    gateway.run(STOP)
    assert sim.stop_latched and store.estop_latch() is None
    gateway.release_estop()
    assert not sim.held
    assert gateway.run(BACK_UP, confirm=YES).executed and sim.speed() > 0.2
    gateway.estop()
    refused = gateway.run(RELEASE, confirm=YES)
    assert not refused.executed and "E-STOP" in refused.reason and sim.e_stopped
    gateway.release_estop()
    assert not sim.held and gateway.run(BACK_UP, confirm=YES).executed and sim.speed() > 0.2


def test_obstacles_topic_reports_a_person(gateway):
    sim = gateway.backend.sim
    sim.undock()
    sim.run_goal(60)
    sim.add_obstacle("person", 5.5, 3.0)
    r = gateway.run("ros2 topic echo /obstacles --once")
    assert r.values["count"] == 1 and r.values["obstacles"][0]["kind"] == "person"
    assert r.values["obstacles"][0]["distance"] == pytest.approx(2.7, abs=0.15)


def test_topic_stats_rates(gateway):
    backend = gateway.backend
    assert backend.sim.t == 0.0
    backend.topic_stats()
    backend.sim.step(1.0)
    stats = {s.name: s for s in backend.topic_stats()}
    assert stats["/odom"].count == 50 and stats["/scan"].count == 10
    assert stats["/battery_status"].count == 1
    assert stats["/scan"].nominal_hz == 10 and stats["/scan"].age_s < 0.1
    assert stats["/cmd_vel"].age_s == math.inf and stats["/plan"].count == 0


def test_interface_show_like_ros2():
    text = interface_show("geometry_msgs/msg/Twist")
    assert "Vector3  linear\n\tfloat64 x\n\tfloat64 y\n\tfloat64 z\n" in text
    scan = interface_show("sensor_msgs/msg/LaserScan")
    assert "std_msgs/Header header\n\tbuiltin_interfaces/Time stamp\n\t\tint32 sec" in scan
    assert "---" in interface_show("std_srvs/srv/Trigger")


def test_echo_text_follows_the_operators_options_and_the_values_stay_whole(gateway):
    r = gateway.run("ros2 topic echo /scan --once -l 5")
    ranges = r.output.split("ranges:\n", 1)[1].split("intensities:")[0]
    assert ranges.count("\n- ") == 6 - 1 and ranges.rstrip().endswith("- '...'")  # 5, then ...
    assert len(r.values["ranges"]) == 360  # what astiop reads is never cut
    r = gateway.run("ros2 topic echo /robot_status --once --no-str")
    state = r.values["state"]  # PyYAML quotes it, as ros2's own yaml.dump does
    assert f"state: '<string length: <{len(state)}>>'" in r.output
    assert f"state: {state}" not in r.output
    r = gateway.run("ros2 topic echo /battery_status --once -l 3")
    assert "location: 2x ..." in r.output  # strings are cut too, with '...'


def test_topic_list_count_is_printed_as_ros2cli_prints_it_on_the_simulator(tmp_path):
    """`ros2 topic list -c` prints the count on every robot (the simulator printed the names)."""
    from astiop.config import load_settings
    from astiop.robot.factory import make_sim_gateway

    gateway = make_sim_gateway(load_settings({}, env={}, path=tmp_path / "none.toml"), None)
    result = gateway.run("ros2 topic list -c")
    assert result.executed and result.output == f"{len(gateway.catalog.topics)}\n", result
    listed = gateway.run("ros2 topic list -t")
    assert "/cmd_vel [geometry_msgs/msg/Twist]\n" in listed.output
