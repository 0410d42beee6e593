"""Which robot a request is about, read without the model, and the fleet's questions answered
from every robot's reported state (a stale robot said to be stale, never its old value)."""

from __future__ import annotations

import pytest

from astiop.agent import gate
from astiop.agent.fleet_words import FleetWordsError, addressed, fleet_answer, fleet_question
from astiop.robot.fleet_watch import FleetRow
from astiop.ros2.validation import Checked

PLACES = {"shipping": (1.0, 1.5), "assembly_station": (4.0, 1.0), "charging_dock": (0.5, 8.0)}


def rows() -> list[FleetRow]:
    made = [
        FleetRow(f"astibot_{i}", f"/astibot_{i}", "astibot", "idle", 0.9 - 0.1 * i,
                 float(i), 1.0, 0.0, 0.0, "", 0.0)
        for i in range(1, 5)
    ]  # fmt: skip
    made[1] = FleetRow("astibot_2", "/astibot_2", "astibot", "navigating", 0.7, 3.9, 1.1,
                       0.0, 0.4, "shipping", 0.0)  # fmt: skip
    made[3] = FleetRow("astibot_4", "/astibot_4", "astibot", "e_stopped", 0.5, 4.0, 1.0,
                       0.0, 0.0, "", 0.0)  # fmt: skip
    made.append(FleetRow("astibot_5", "/astibot_5", battery=0.05, x=9.0, y=9.0, age_s=12.0))
    return made


@pytest.mark.parametrize(
    ("said", "name", "to_robot"),
    [
        ("send astibot 3 to shipping", "astibot_3", "send the robot to shipping"),
        ("send astibot_3 to shipping", "astibot_3", "send the robot to shipping"),
        ("stop robot 3", "astibot_3", "stop the robot"),
        ("send robot number two to shipping", "astibot_2", "send the robot to shipping"),
        ("what is Astibot-4's battery?", "astibot_4", "what is the robot's battery?"),
        # idle and heard just now: astibot_2 and 4 are closer, navigating and stopped
        ("send the nearest idle robot to the assembly station", "astibot_3",
         "send the robot to the assembly station"),
        ("send the one at shipping to the charging dock", "astibot_1",
         "send the robot to the charging dock"),
    ],
)  # fmt: skip
def test_the_robot_a_request_names_is_found_and_the_request_said_to_it(said, name, to_robot):
    got = addressed(said, rows(), PLACES)
    assert got is not None and (got.name, got.request) == (name, to_robot), got


def test_a_request_naming_no_robot_or_two_robots():
    assert addressed("send the robot to shipping", rows(), PLACES) is None
    assert addressed("go to x 1 y 2", rows(), PLACES) is None
    with pytest.raises(FleetWordsError, match="one robot per request: this one names astibot_1"):
        addressed("send astibot 1 and astibot 2 to shipping", rows(), PLACES)
    with pytest.raises(FleetWordsError, match="nearest to where"):
        addressed("send the nearest robot somewhere", rows(), PLACES)
    with pytest.raises(FleetWordsError, match="no robot is at charging_dock"):
        addressed("send the one at charging dock to shipping", rows(), PLACES)


def test_fleet_questions_are_answered_from_what_each_robot_reported():
    assert fleet_question("what is the battery level?") is None
    assert fleet_question("send the robot to shipping") is None
    kind = fleet_question("Which robot has the lowest battery?")
    said = fleet_answer(kind, rows())
    # astibot_5 reads 5 % but was last heard 12 s ago: stale, not the answer
    assert said.startswith("astibot_4 has the lowest battery: 50.0 %."), said
    assert "astibot_5: stale, last heard 12 s ago" in said and "5 %" not in said
    said = fleet_answer(fleet_question("where are all the robots?"), rows())
    assert "astibot_2 at x 3.90 m, y 1.10 m (navigating)" in said
    assert said.startswith("5 robots, 4 reporting now:")
    assert fleet_question("which robot has the most charge left? battery") == "highest_battery"


def test_the_gate_refuses_a_plan_that_touches_another_robot():
    from astiop.ros2.grammar import parse
    from tests.unit.test_profile import tb3_graph

    graph, two = tb3_graph("/tb3_1"), tb3_graph("/tb3_2")
    graph.topics.update(two.topics)
    pub = "ros2 topic pub --once /tb3_2/cmd_vel geometry_msgs/msg/TwistStamped '{}'"
    other = Checked(pub, parse(pub), True, namespace="/tb3_1")
    echo = "ros2 topic echo /tb3_1/odom --once"
    own = Checked(echo, parse(echo), True, namespace="/tb3_1")
    assert gate.other_robot([own], graph) is None
    assert gate.other_robot([own, other], graph) == (
        "this request is about tb3_1; /tb3_2/cmd_vel is another robot's (tb3_2)"
    )
