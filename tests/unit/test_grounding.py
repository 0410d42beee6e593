"""Answers held to what the robot reported: claims checked, loops cut, arrival told when it happens."""

import time

import pytest

from astiop.agent import grounding
from astiop.agent.facts import facts_of
from astiop.agent.models.llm import OpenAIClient
from astiop.agent.models.reply_stream import repeating
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.transports.base import Execution
from astiop.transports.simulator.backend import SimBackend
from tests.scripted_llm import ScriptedLLM
from tests.unit.test_agent import make_agent

READ = "ros2 topic echo {} --once"


@pytest.fixture(scope="module")
def results():
    """Real results from a seeded simulator: pose, battery, status, obstacles, conveyor."""
    sim = Simulator(seed=3, start=(8.0, 8.75, 0.0), battery_soc=0.62)
    sim.add_obstacle("person", 11.0, 8.75)
    sim.step(0.5)
    gateway = RobotGateway(SimBackend(sim, None), SafetyPolicy())
    topics = ["/robot_pose", "/battery_status", "/robot_status", "/obstacles", "/conveyor/status"]
    out = {t: gateway.run(READ.format(t)) for t in topics}
    assert all(ex.executed and not ex.error for ex in out.values())
    return out


def check(answer, *executions, request="?"):
    facts = facts_of(request, list(executions))
    return grounding.unsupported(answer, facts) or grounding.missing(answer, list(executions))


def test_an_answer_with_the_reported_facts_is_kept(results):
    pose, bat = results["/robot_pose"].values, results["/battery_status"].values
    assert (
        check(f"The robot is at x {pose['x']:.2f} m, y {pose['y']:.2f} m.", results["/robot_pose"])
        is None
    )
    assert check(f"Battery at {bat['percentage'] * 100:.0f}%.", results["/battery_status"]) is None
    assert check("One obstacle: a person about 3 m ahead.", results["/obstacles"]) is None
    assert (
        check(
            "The robot is idle and the conveyor is empty.",
            results["/robot_status"],
            results["/conveyor/status"],
        )
        is None
    )


CLAIMS = [
    # (topic read, answer, what the reason names)
    ("/obstacles", "The robot is blocked by a series of obstacles, including a drone.", "drone"),
    ("/obstacles", "There are 4 obstacles around the robot, one person.", "4"),
    ("/obstacles", "No obstacles; the path is clear.", "clear"),
    ("/battery_status", "The battery is at 90 %.", "90"),
    ("/battery_status", "The battery is charging, 62 % left.", "charging"),
    ("/robot_pose", "The robot has arrived at the assembly station.", "arriv"),
    ("/robot_pose", "The robot's destination location was located at [address].", "position"),
    ("/robot_status", "The robot is navigating to shipping.", "navigating"),
    ("/robot_status", "All good.", "state"),
    ("/conveyor/status", "The conveyor is loaded.", "loaded"),
]


@pytest.mark.parametrize("topic,answer,named", CLAIMS)
def test_a_claim_the_results_do_not_support_is_caught(results, topic, answer, named):
    reason = check(answer, results[topic])
    assert reason is not None and named in reason


def test_numbers_from_the_request_may_be_repeated(results):
    assert (
        check(
            "Going to x 12.5, y 4 is not possible from here; the robot is idle.",
            results["/robot_status"],
            request="go to x 12.5 y 4",
        )
        is None
    )


def test_the_factual_answer_states_only_what_the_results_hold(results):
    executions = list(results.values())
    answer = grounding.factual_answer(executions)
    assert check(answer, *executions) is None
    assert "1 obstacle(s) detected: person" in answer


@pytest.mark.parametrize(
    "text,loops",
    [
        ("assembly_station " * 6, True),
        ("The robot is at x 2. " * 3, True),
        ("The robot is at x 2.5 m, y 3.0 m, facing east. The battery is 85 %.", False),
        ("[0.0, 0.0, 0.0, 0.0]", False),
    ],
)
def test_a_loop_is_recognised(text, loops):
    assert repeating(text) is loops


@pytest.fixture
def llm():
    s = ScriptedLLM("openai")
    yield s
    s.close()


async def test_a_server_that_loops_forever_is_cut(llm):
    llm.mode = "endless"
    client = OpenAIClient(llm.url, "scripted")
    c = await client.chat([{"role": "user", "content": "hi"}], max_tokens=500, guard=True)
    assert c.finish_reason == "repetition" and len(c.text.split()) <= 8


async def test_a_server_that_ignores_the_cap_is_cut_at_it(llm):
    llm.mode, llm.endless = "endless", lambda i: f"w{i} "
    client = OpenAIClient(llm.url, "scripted")
    c = await client.chat([{"role": "user", "content": "hi"}], max_tokens=40, guard=True)
    assert c.finish_reason == "length" and len(c.text.split()) <= 50


async def test_a_server_that_never_ends_is_cut_at_the_deadline(llm):
    llm.mode, llm.endless, llm.delay_s = "endless", (lambda i: f"w{i} "), 0.05
    client = OpenAIClient(llm.url, "scripted")
    t0 = time.monotonic()
    c = await client.chat(
        [{"role": "user", "content": "hi"}], max_tokens=10**6, guard=True, deadline_s=0.5
    )
    assert c.finish_reason == "deadline" and time.monotonic() - t0 < 5.0


async def test_a_false_answer_is_replaced_and_both_are_recorded(llm, store):
    llm.replies = [
        '{"commands": ["ros2 topic echo /obstacles --once"]}',
        "The robot is blocked by a series of obstacles, including a drone.",
    ]
    agent = make_agent(llm, store)
    result = await agent.turn("is anything blocking the robot?")
    assert result.answer == "0 obstacles detected"
    assert result.grounding.startswith("replaced: it says 'blocked'")
    row = store.db.execute(
        "SELECT answer, model_answer, grounding FROM interactions WHERE id = ?",
        [result.interaction_id],
    ).fetchone()
    assert row[0] == "0 obstacles detected" and "drone" in row[1] and "blocked" in row[2]


async def test_a_looping_answer_is_replaced(llm, store):
    llm.replies = ['{"commands": ["ros2 topic echo /robot_pose --once"]}']
    llm.default = "assembly_station " * 200
    agent = make_agent(llm, store)
    result = await agent.turn("where is the robot?")
    assert "repeated itself" in result.grounding
    assert result.answer.startswith("position x ")


async def test_raw_interpretation_keeps_the_models_words(llm, store):
    llm.replies = ['{"commands": ["ros2 topic echo /obstacles --once"]}', "A drone blocks it."]
    agent = make_agent(llm, store)
    agent.interpreter.style = "raw"
    result = await agent.turn("is anything blocking the robot?")
    assert result.answer == "A drone blocks it." and result.grounding == "raw"


async def test_navigation_is_reported_started_then_arrived_as_a_follow_up(llm, store):
    llm.replies = [
        '{"commands": ["ros2 service call /goto_position astiop_msgs/srv/GotoPosition '
        '\\"{name: \'inspection_zone_a\'}\\""]}',
        "The robot has arrived at inspection zone A.",
    ]
    agent = make_agent(llm, store)
    result = await agent.turn("send the robot to inspection zone A")
    assert result.started.startswith("goal accepted: inspection_zone_a, ")
    assert "m to go" in result.started
    assert "arrived" in result.grounding and "arrived" not in result.answer
    follow = await agent.follow_up(result)
    assert follow.startswith("arrived: inspection_zone_a (x 1") and result.outcome == "succeeded"
    x = float(follow.split("(x ")[1].split(",")[0])
    assert abs(x - 15.0) < 0.1
    row = store.db.execute(
        "SELECT outcome FROM interactions WHERE id = ?", [result.interaction_id]
    ).fetchone()
    assert row[0] == "succeeded"


def test_each_sentence_is_checked_and_only_the_true_ones_stay(results):
    """Issue 24: a sentence stays if it states a checked fact and nothing unsupported; a name
    the results never mention (a service, an error) makes it unsupported."""
    bat = results["/battery_status"]
    pct = bat.values["percentage"] * 100
    facts = facts_of("what is the battery level?", [bat])
    answer = (
        f"The battery is at {pct:.1f} %. "
        "This is measured by the EchoBite-USB system, see the ROS documentation. "
        "A GotoPosition exception occurs when another robot sends data. "
        "I hope this helps!"
    )
    text, reason, dropped = grounding.grounded(answer, facts, [bat])
    assert text == f"The battery is at {pct:.1f} %." and reason is None and dropped == 3
    # nothing true left: the answer cannot stand, and the reason names the first false claim
    text, reason, _ = grounding.grounded("A GotoPosition exception occurred.", facts, [bat])
    assert text == "" and "GotoPosition" in reason
    # a true sentence that leaves out what the robot reported does not stand alone
    status = results["/robot_status"]
    facts = facts_of("status and battery?", [status, bat])
    _, reason, _ = grounding.grounded("The robot is idle.", facts, [status, bat])
    assert reason and "battery" in reason


async def test_the_models_true_sentences_are_kept_and_the_rest_dropped(llm, store):
    llm.replies = [
        '{"commands": ["ros2 topic echo /battery_status --once"]}',
        "The battery is at 85.0 %. The reason can be found in the ROS documentation, "
        "which describes an exception called GotoPosition.",
    ]
    result = await make_agent(llm, store).turn("What is the battery level?")
    assert result.answer == "The battery is at 85.0 %."
    assert result.grounding == "kept, 1 part(s) dropped"


def test_the_parts_of_a_sentence_are_held_one_by_one():
    """A small model joins a true part to a false one; the false part goes, the true one stays,
    and a commanded or accepted result is never said as done."""
    goto = Execution(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'shipping'}\"",
        True,
        kind="actuate",
        executed=True,
        values={"success": True, "message": "navigating to shipping, 36.5 m along the path"},
        provenance="accepted",
    )
    facts = facts_of("go to shipping", [goto], None, ["goal accepted: shipping, 36.5 m"])
    cases = {
        "The robot is on its way, and it has not been on its way for 36.5 m.": (
            "The robot is on its way.", 1),
        "The goal to shipping was accepted; the robot is on its way with 36.5 m to go.": (
            "The goal to shipping was accepted; the robot is on its way with 36.5 m to go.", 0),
        "It successfully arrived at shipping, but the goal was accepted.": (
            "The goal was accepted.", 1),
        "The robot is going 36.5 m per second; it was accepted.": ("It was accepted.", 1),
    }  # fmt: skip
    for answer, (kept, dropped) in cases.items():
        text, reason, n = grounding.grounded(answer, facts, [goto])
        assert (text, reason, n) == (kept, None, dropped), answer


def test_a_goal_no_result_speaks_of_is_not_said():
    """Seen on the console: a bare /stop answered "The robot stopped, and its goal was
    stopped." with no goal anywhere; a goal the robot reported stays."""
    stop = Execution(
        "ros2 service call /stop std_srvs/srv/Trigger",
        True,
        kind="actuate",
        executed=True,
        values={"success": True, "message": "stopped"},
    )
    facts = facts_of("stop the goal", [stop])  # the request's words are no report
    text, reason, n = grounding.grounded(
        "The robot stopped, and its goal was stopped.", facts, [stop]
    )
    assert (text, reason, n) == ("The robot stopped.", None, 1)
    canceled = Execution(
        stop.command, True, kind="actuate", executed=True,
        values={"success": True, "message": "stopped; goal canceled"},
    )  # fmt: skip
    facts = facts_of("stop", [canceled])
    answer = "The robot stopped, and its goal was canceled."
    assert grounding.grounded(answer, facts, [canceled]) == (answer, None, 0)
