"""Command forms per distro, from ros2cli's argparse definitions on the humble and jazzy branches
(ros2topic/verb/{echo,pub,hz,list}.py, ros2service/verb/call.py, ros2action/verb/send_goal.py,
ros2interface/verb/show.py, ros2param/verb/{list,set}.py, ros2node/verb/list.py)."""

import pytest

from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.render import sent_argv
from astiop.ros2.validation import validate

CAT = astibot_catalog()
BOTH = ("humble", "jazzy")

# (command, distros where it is valid)
FORMS = [
    ("ros2 topic echo /battery_status --once", BOTH),
    ("ros2 topic echo /battery_status -1", ()),  # echo has no -1: argparse takes it as the type
    ("ros2 topic echo /battery_status --once --timeout 5", ("jazzy",)),  # Jazzy added --timeout
    ("ros2 topic echo /scan --once --full-length", BOTH),
    ("ros2 topic echo /scan --once -f -l 10 --no-str --flow-style", BOTH),
    ("ros2 topic echo /scan --once --csv --field ranges", BOTH),
    ("ros2 topic echo /scan --once --qos-profile sensor_data --qos-depth 5", BOTH),
    ("ros2 topic echo /scan --once --qos-history keep_last --qos-durability volatile", BOTH),
    ("ros2 topic echo /scan --once --no-daemon --spin-time 2", BOTH),
    ("ros2 topic echo /scan --once --include-message-info", ("jazzy",)),
    ("ros2 topic echo /scan --once --lost-messages", ("humble",)),  # deprecated, Humble only
    ("ros2 topic list -t -c", BOTH),
    ("ros2 topic list -v", BOTH),
    ("ros2 topic hz /scan --window=20", BOTH),
    ("ros2 topic hz /scan -w20", BOTH),
    ("ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{}'", BOTH),
    ("ros2 topic pub -t 5 -r2 /cmd_vel geometry_msgs/msg/Twist '{}'", BOTH),
    ("ros2 topic pub --rate=2 -t 5 /cmd_vel geometry_msgs/msg/Twist '{}'", BOTH),
    ("ros2 topic pub --once -t 5 /cmd_vel geometry_msgs/msg/Twist '{}'", ()),  # exclusive
    ("ros2 topic pub -r nan -t 5 /cmd_vel geometry_msgs/msg/Twist '{}'", ()),
    ("ros2 topic pub -r inf -t 5 /cmd_vel geometry_msgs/msg/Twist '{}'", ()),
    ("ros2 topic pub --once --max-wait-time-secs 2 /cmd_vel geometry_msgs/msg/Twist", ("jazzy",)),
    ("ros2 service call /stop std_srvs/srv/Trigger", BOTH),
    ("ros2 service call /stop", ()),  # the type is required on both
    ("ros2 service list -c", BOTH),
    (
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        "'{pose: {pose: {position: {x: 5.0, y: 3.0}}}}' -f",
        BOTH,
    ),
    ("ros2 interface show sensor_msgs/msg/BatteryState --no-comments", BOTH),
    ("ros2 interface show sensor_msgs/msg/BatteryState --all-comments", BOTH),
    ("ros2 interface show sensor_msgs/BatteryState", ()),  # needs pkg/msg/Name
    ("ros2 node list -a -c", BOTH),
    ("ros2 node info navigator", BOTH),  # sent as /navigator
    ("ros2 param list --filter max", BOTH),
    ("ros2 param set /astibot_base max_linear_speed 1", BOTH),  # sent as 1.0
    ("ros2 param get /astibot_base max_linear_speed --timeout 2", ("jazzy",)),
    ("ros2 bag record /scan", ()),  # not a verb astiop runs
]


@pytest.mark.parametrize("distro", BOTH)
@pytest.mark.parametrize("command,valid_on", FORMS)
def test_command_forms_per_distro(command, valid_on, distro):
    checked = validate(command, CAT, distro)
    assert checked.valid == (distro in valid_on), checked.reason
    if not checked.valid:
        assert checked.reason and "\n" not in checked.reason


def test_errors_read_like_the_cli_with_a_suggestion():
    reason = validate("ros2 topic echo /scan --once --ful-length", CAT, "jazzy").reason
    assert "unrecognized arguments: --ful-length" in reason and "--full-length" in reason
    reason = validate("ros2 topic echo /scan --once --timeout 5", CAT, "humble").reason
    assert "ros2 topic echo (humble)" in reason
    reason = validate("ros2 topic echo /battery_status -1", CAT, "jazzy").reason
    assert "--once" in reason


def test_what_is_sent_is_rebuilt_from_the_parse():
    def sent(command: str) -> list[str]:
        checked = validate(command, CAT, "jazzy")
        assert checked.valid, checked.reason
        return sent_argv(checked)

    assert sent("ros2 node info navigator") == ["node", "info", "/navigator"]
    assert sent("ros2 param set astibot_base max_linear_speed 1")[-1] == "1.0"
    goal = sent(
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        "'{pose: {pose: {position: {x: 5.0, y: 3.0}}}}'"
    )
    assert "frame_id: map" in goal[-1]
    call = sent("ros2 service call stop std_srvs/Trigger")
    assert call[:4] == ["service", "call", "/stop", "std_srvs/srv/Trigger"]


def test_a_stamped_cmd_vel_gets_the_same_clamp_and_a_fresh_stamp(store):
    from dataclasses import replace

    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.ros2.render import STAMPED
    from astiop.sim.simulator import Simulator
    from astiop.transports.simulator.backend import SimBackend

    backend = SimBackend(Simulator(seed=0), store)
    backend.catalog.topics["/cmd_vel"] = replace(backend.catalog.topics["/cmd_vel"], type=STAMPED)
    gateway = RobotGateway(backend, SafetyPolicy(max_linear=0.8))
    review = gateway.review(
        f"ros2 topic pub --once /cmd_vel {STAMPED} '{{twist: {{linear: {{x: 3.0}}}}}}'"
    )
    assert review.allowed and review.checked.message["twist"]["linear"]["x"] == 0.8
    sent = sent_argv(review.checked)
    assert sent[-2] == STAMPED and "header: auto" in sent[-1] and "x: 0.8" in sent[-1]
    result = gateway.drive(2.0, 0.0, 0.0)  # teleop on a stamped base
    assert result.executed and result.values["twist"]["linear"]["x"] == 0.8


def test_types_are_as_each_distro_defines_them():
    """Read from `git show humble:` / `jazzy:` of common_interfaces and navigation2."""
    from astiop.ros2.interfaces import interface_show

    humble = interface_show("nav2_msgs/action/NavigateToPose", "humble")
    jazzy = interface_show("nav2_msgs/action/NavigateToPose", "jazzy")
    assert "std_msgs/Empty result" in humble and "error_code" not in humble
    assert "uint16 NONE=0\nuint16 error_code\nstring error_msg" in jazzy
    battery_h = interface_show("sensor_msgs/msg/BatteryState", "humble")
    battery_j = interface_show("sensor_msgs/msg/BatteryState", "jazzy")
    assert "POWER_SUPPLY_TECHNOLOGY_LIMN = 6" in battery_h and "VRLA" not in battery_h
    assert "uint8 POWER_SUPPLY_TECHNOLOGY_VRLA = 8" in battery_j
    assert "uint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE = 8" in battery_h


@pytest.mark.parametrize("distro,technology", [("humble", 0), ("jazzy", 8)])
def test_the_astibot_reports_its_lead_acid_battery_where_the_distro_can_say_so(
    monkeypatch, distro, technology
):
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.sim.simulator import Simulator
    from astiop.transports.simulator.backend import SimBackend

    monkeypatch.setenv("ROS_DISTRO", distro)
    gateway = RobotGateway(SimBackend(Simulator(seed=0), None), SafetyPolicy())
    r = gateway.run("ros2 topic echo /battery_status --once")
    assert r.values["power_supply_technology"] == technology
