"""Each question answered about what it asks (a field, a parameter, the graph, the places, why
the robot is still, the journal, astiop itself), or declined in one line; never a reading of
another role in its place. Real turns on seeded simulators; the figures are the simulator's."""

import math

import pytest

from astiop.agent.intent import classify
from astiop.agent.models.specs import open_endpoint
from astiop.agent.subject import subjects_of
from astiop.agent.turn import Agent
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend
from tests.scripted_llm import ScriptedLLM

PLACES = {"shipping": (37.6, 4.0), "charging_dock": (2.5, 3.0), "cps_storage": (37.6, 21.0)}


def agent_on(sim, store, model="rules", places=PLACES):
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy())
    return Agent(gateway, open_endpoint(model), store, confirm=lambda _c: True, places=places)


async def ask(text, store, sim=None):
    sim = sim or Simulator(seed=3, start=(10.0, 8.0, math.pi / 2))
    sim.step(0.2)
    return sim, await agent_on(sim, store).turn(text)


def ran(result):
    return [c.command for c in result.commands if c.executed]


async def test_a_battery_field_is_answered_with_that_field(store):
    _, r = await ask("what temperature is the battery at?", store)
    assert ran(r) == ["ros2 topic echo /battery_status --once"]
    assert "temperature is 25.00 °C" in r.answer


async def test_a_field_the_robot_does_not_report_is_said_missing_with_what_it_reports(store):
    _, r = await ask("how warm are the wheel motors?", store)
    assert "reports no motor temperature" in r.answer
    assert "25 °C temperature" in r.answer  # what it does report, not offered as the answer


async def test_the_heading_is_the_pose_heading(store):
    _, r = await ask("which way does the robot point?", store)
    assert "faces 90°" in r.answer and "north" in r.answer


async def test_the_lidar_range_is_its_scan_range_max(store):
    sim, r = await ask("what is the maximum range of the laser scanner?", store)
    assert ran(r) == ["ros2 topic echo /scan --once"]
    assert f"{r.commands[0].values['range_max']:g} m" in r.answer


async def test_distance_to_a_place_is_the_straight_line_from_the_pose(store):
    sim, r = await ask("how far away is cps storage?", store)
    want = math.dist(sim.pose[:2], PLACES["cps_storage"])
    assert f"{want:.1f} m from cps_storage" in r.answer and "straight line" in r.answer


async def test_the_nearest_place_is_computed(store):
    _, r = await ask("what is the closest station to the robot?", store)
    assert r.answer.startswith("[rules] The nearest place is charging_dock")


async def test_distance_between_two_places_needs_no_read(store):
    _, r = await ask("distance between shipping and cps storage?", store)
    assert ran(r) == [] and "17.0 m apart" in r.answer


async def test_an_unknown_place_is_declined_with_the_known_ones(store):
    _, r = await ask("how far is it to the loading bay on mars?", store)
    assert "names no place the robot knows" in r.answer and "shipping" in r.answer


async def test_top_speed_is_the_robots_own_parameter(store):
    sim, r = await ask("how fast can the robot go at most?", store)
    assert "ros2 param get /astibot_base max_linear_speed" in ran(r)
    assert f"max_linear_speed is {sim.gains.v_max:g}" in r.answer


async def test_outside_the_robot_is_declined_with_no_read(store):
    _, r = await ask("will it rain tomorrow?", store)
    assert r.commands == [] and "outside the robot" in r.answer


async def test_the_graph_is_listed(store):
    _, r = await ask("which services does the robot offer?", store)
    assert ran(r) == ["ros2 service list"] and "/dock" in r.answer


async def test_who_publishes_a_topic_is_read_from_each_nodes_info(store):
    _, r = await ask("which node publishes the scan?", store)
    assert r.answer == "[rules] /lidar_driver publishes /scan (from the info of 8 nodes)."


async def test_a_topics_type_is_its_own(store):
    _, r = await ask("what message type is /odom?", store)
    assert ran(r) == ["ros2 topic info /odom"] and "nav_msgs/msg/Odometry" in r.answer


async def test_the_estop_state_is_the_robots_and_astiops_latch(store):
    sim = Simulator(seed=3)
    sim.e_stopped = True
    sim.step(0.2)
    _, r = await ask("is the robot e-stopped?", store, sim)
    assert "The robot is E-stopped" in r.answer and "latch is released" in r.answer


async def test_another_components_current_is_said_missing_not_the_batterys(store):
    _, r = await ask("what current are the motors drawing?", store)
    assert "reports no motor current" in r.answer


async def test_a_robot_without_a_camera_says_so_and_is_missing_nothing(store):
    sim, r = await ask("what is the camera showing?", store, Simulator(seed=3, camera=None))
    assert r.commands == [] and "publishes no camera image" in r.answer
    assert agent_on(sim, store).gateway.profile.missing() == ["map"]


async def test_why_a_docked_robot_is_still(store):
    sim = Simulator(seed=3)  # starts docked, charging
    _, r = await ask("why is the robot standing still?", store, sim)
    assert "docked" in r.answer and "no goal" in r.answer


async def test_time_to_full_is_computed_from_charge_capacity_and_current(store):
    sim = Simulator(seed=3, battery_soc=0.5)
    _, r = await ask("how long until the battery is fully charged?", store, sim)
    v = r.commands[0].values
    minutes = round((v["capacity"] - v["charge"]) / v["current"] * 60)
    assert f"{minutes // 60} h {minutes % 60:02d} min" in r.answer or f"{minutes} min" in r.answer


async def test_the_journal_says_what_was_asked_before(store):
    sim = Simulator(seed=3)
    agent = agent_on(sim, store)
    await agent.turn("what is the battery level?")
    r = await agent.turn("what has the robot done in the past hour?")
    assert "1 request(s)" in r.answer and "battery level" in r.answer


async def test_a_model_is_not_asked_for_a_subject_it_cannot_compute(store):
    llm = ScriptedLLM("openai")
    try:
        llm.replies = ['{"commands": ["ros2 topic echo /battery_status --once"]}']
        sim = Simulator(seed=3)
        r = await agent_on(sim, store, f"openai:scripted@{llm.url}").turn("list the topics")
        assert llm.requests == [] and "/scan" in r.answer and not r.answer.startswith("[rules")
    finally:
        llm.close()


@pytest.mark.parametrize(
    "text",
    ["where is the robot?", "what is the battery level?", "go to shipping", "show me the path"],
)
def test_plain_readings_and_actions_keep_their_plans(text):
    assert subjects_of(text, classify(text, list(PLACES)), list(PLACES)) is None


@pytest.mark.parametrize(
    ("text", "kind", "what"),
    [
        ("tell me some jokes", "outside", ""),
        ("can you write poems?", "outside", ""),
        ("what are you capable of?", "capabilities", ""),
        ("I'd like to know what you're able to do", "capabilities", ""),
        ("how long a trip is it to shipping?", "places", "distance"),
        ("what is the farthest distance the lidar reaches?", "field", "scan.range_max"),
        ("what's the minimum distance the laser can measure?", "field", "scan.range_min"),
        ("is the battery running hot?", "field", "battery.temperature"),
        ("how much longer till the pack is charged up?", "field", "battery.time_to_full"),
        ("what has it got up to in the past 2 hours?", "journal", ""),
        ("give me a recap of what was done today", "journal", ""),
        ("what is the gap between the robot and shipping?", "places", "distance"),
        ("up to what range can the laser see?", "field", "scan.range_max"),
        ("amuse me", "outside", ""),
        ("will I need an umbrella tonight?", "outside", ""),
        ("what is its compass heading?", "field", "pose.heading"),
        ("report the robot's bearing", "field", "pose.heading"),
        ("what kinds of questions do you answer?", "capabilities", ""),
        ("how quickly can it drive flat out?", "parameter", "max linear speed"),
    ],
)
def test_more_ways_of_asking_find_the_same_subject(text, kind, what):
    found = subjects_of(text, classify(text, list(PLACES)), list(PLACES))
    assert found is not None and [(s.kind, s.what) for s in found] == [(kind, what)], found


async def test_one_subject_asked_twice_is_answered_once(store):
    _, r = await ask("is the battery getting hot? what is its temperature?", store)
    assert r.answer.count("temperature is 25.00 °C") == 1, r.answer


async def test_a_nodes_parameters_are_listed_when_none_is_named(store):
    _, r = await ask("which parameters has the lidar driver got?", store)
    assert r.answer.startswith("[rules] /lidar_driver has ") and "range_max" in r.answer, r.answer
