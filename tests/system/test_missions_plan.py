"""Missions read from plain words, the `multistep` suite and its scoring by order, and
`astiop chat --no-wait` handing a mission to a process of its own."""

import asyncio
import time

import pytest

from astiop.agent.mission_plan import steps_for, until_stopped
from astiop.bench import multistep, runner
from astiop.bench.report import load_report
from astiop.bench.suites import RobotCase
from astiop.config import load_settings
from astiop.missions.steps import describe
from astiop.store import Store
from tests.cli_runner import run_cli

PLACES = {
    n: (0.0, 0.0)
    for n in [
        "assembly_station",
        "charging_dock",
        "cps_storage",
        "inspection_zone_a",
        "inspection_zone_b",
        "shipping",
    ]
}


@pytest.mark.parametrize(
    "request_text,plan",
    [
        (
            "go to shipping, then inspection zone a, then dock",
            "1. go to shipping; 2. go to inspection_zone_a; 3. dock",
        ),
        (
            "patrol between the assembly station and shipping twice",
            "1. go to assembly_station; 2. go to shipping; 3. go to assembly_station; "
            "4. go to shipping",
        ),
        (
            "if the battery is under 30 %, dock first, then go to cps storage",
            "1. if battery under 30 %: dock; 2. go to cps_storage",
        ),
        (
            "undock, go to cps storage and load, then go to shipping and unload, then dock",
            "1. undock; 2. go to cps_storage; 3. load; 4. go to shipping; 5. unload; 6. dock",
        ),
        (
            "go to shipping, then wait 5 seconds, then go to cps storage",
            "1. go to shipping; 2. wait 5 s; 3. go to cps_storage",
        ),
        (
            "if the way is clear, go to shipping, then dock",
            "1. if no obstacle is seen: go to shipping; 2. dock",
        ),
        ("go to the moon, then dock", "1. go to moon; 2. dock"),
    ],
)
def test_plain_requests_become_steps_in_their_order(request_text, plan):
    assert describe(steps_for(request_text, PLACES)) == plan


@pytest.mark.parametrize(
    "request_text",
    [
        "go to shipping",  # one goal: a plain turn
        "what is the battery level?",
        "go to shipping and unload there",  # one goal and a service: the turn waits between
        "move forward, then go to shipping",  # a motion is no mission step: the model plans
        "swing by shipping and afterwards park at the charger",  # not plain: the model plans
    ],
)
def test_requests_that_are_not_plain_missions(request_text):
    assert steps_for(request_text, PLACES) is None


@pytest.mark.parametrize(
    "request_text,plan",
    [
        (
            "patrol between shipping and the assembly station until I stop it",
            "1. go to shipping; 2. go to assembly_station; repeated until stopped",
        ),
        (
            "go to shipping, then inspection zone a, forever",
            "1. go to shipping; 2. go to inspection_zone_a; repeated until stopped",
        ),
        (
            "patrol between cps storage and shipping continuously",
            "1. go to cps_storage; 2. go to shipping; repeated until stopped",
        ),
        (
            "patrol between shipping and inspection zone b until told to stop",
            "1. go to shipping; 2. go to inspection_zone_b; repeated until stopped",
        ),
        (
            "go to shipping, then dock",  # no repeat: once, as before
            "1. go to shipping; 2. dock",
        ),
    ],
)
def test_until_i_stop_it_repeats_with_no_count(request_text, plan):
    text, forever = until_stopped(request_text)
    assert describe(steps_for(text, PLACES), forever) == plan


def case(**outcome) -> RobotCase:
    return RobotCase("t", "sequence", "r", ("service call /dock",), outcome=outcome)


def test_order_is_scored_and_a_false_claim_zeroes_the_interpretation():
    c = case(visits=["shipping", "inspection_zone_a"], docked=True)
    steps = [
        {"label": "go to shipping", "status": "succeeded"},
        {"label": "go to inspection_zone_a", "status": "succeeded"},
    ]
    mission = {"steps": steps}
    assert multistep.score(c, ["shipping", "inspection_zone_a"], True, mission, "")[:2] == (
        100.0,
        100.0,
    )
    # out of order: wrong, though every place was visited
    command, interpretation, _ = multistep.score(
        c, ["inspection_zone_a", "shipping"], True, mission, ""
    )
    assert command == 0.0
    # a step the answer says was reached but the robot never reached
    command, interpretation, details = multistep.score(c, ["shipping"], True, mission, "")
    assert command == 50.0 and interpretation == 0.0
    assert details["claims"] == {"reached shipping": True, "reached inspection_zone_a": False}


@pytest.mark.slow
def test_the_multistep_suite_runs_with_the_rules_and_is_scored_by_order(store, tmp_path):
    settings = load_settings({"llm": {"threads": 1}}, env={}, path=tmp_path / "none.toml")
    config = runner.RunConfig(stage=2, models=["rules"], suite="multistep")
    suite = runner.suite_of(store, config)
    assert len(suite.cases) >= 24
    assert {c.category for c in suite.cases} >= {"sequence", "repeat", "condition", "failure"}
    run_id = runner.create_run(store, config)
    asyncio.run(runner.run(store, settings, config, run_id))
    (result,) = load_report(store, run_id).results
    assert result.cases == len(suite.cases) and result.errors == 0
    # every plain request is right; the two that are not plain words are not (no model)
    wrong = sorted(k for k, v in result.by_case.items() if v < 100)
    assert wrong == ["seq11", "seq12"], result.by_case
    for failing in ("fai01", "fai02", "fai03"):
        assert result.by_case[failing] == 100  # the failure happened and was reported


def test_chat_no_wait_hands_the_mission_to_a_process_of_its_own(tmp_path, monkeypatch):
    db = tmp_path / "nowait.db"
    monkeypatch.setenv("ASTIOP_DB", str(db))
    out = run_cli("chat", "--model", "rules", "--yes", "--no-wait", "go to shipping, then dock")
    assert out.returncode == 0, out.stderr
    assert "mission 1 is driven by a process of its own" in out.stdout
    store = Store(db)
    deadline = time.monotonic() + 60
    while store.mission(1)["status"] in ("queued", "running") and time.monotonic() < deadline:
        time.sleep(0.2)
    assert store.mission(1)["status"] == "succeeded", store.mission_steps(1)
    assert [s["status"] for s in store.mission_steps(1)] == ["succeeded", "succeeded"]
    assert (tmp_path / "logs" / "mission-1.log").read_text().count("✓ step") == 2
    store.close()
