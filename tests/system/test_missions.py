"""Missions on the in-process simulator: steps in order, each ended as the robot reported it,
stored with the robot's pose; failures, the E-STOP, replacement, cancel, interruption, resume."""

import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.missions import view
from astiop.missions.runner import MissionError, MissionRunner
from astiop.missions.steps import Condition, Step
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from tests.cli_runner import run_cli

YES = lambda _c: True  # noqa: E731


def gateway_for(store, realtime=False, speed=1.0):
    backend = SimBackend(Simulator(seed=0), store, realtime=realtime, speed=speed)
    gateway = RobotGateway(backend, SafetyPolicy(), store=store)
    if realtime:
        gateway.start()
    return gateway


def places(store):
    return {loc.name: (loc.x, loc.y) for loc in store.list_locations()}


def wait_for_step(store, mission_id, seq, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        steps = store.mission_steps(mission_id)
        if steps[seq]["status"] == "running":
            return
        time.sleep(0.02)
    raise AssertionError(f"step {seq + 1} never started: {store.mission_steps(mission_id)}")


def at(step, xy, tol=0.3):
    return step["x"] is not None and math.dist((step["x"], step["y"]), xy) <= tol


async def test_a_sequence_is_a_mission_run_in_order_not_all_goals_at_once(store):
    """The bug of issue 36: the three goals were sent at once, each replacing the one before,
    and the answer said a goal the robot never reached had succeeded."""
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("go to shipping, then go to inspection zone a, then dock")
    assert result.commands == []  # nothing sent by the turn itself
    assert result.answer.startswith(f"mission {result.mission_id} started: 3 steps")
    assert "succeeded" not in result.answer
    assert agent.missions.wait(60)
    m = view.as_json(store, result.mission_id)
    assert m["status"] == "succeeded", m
    steps = store.mission_steps(result.mission_id)
    assert [s["status"] for s in steps] == ["succeeded"] * 3
    p = places(store)
    assert at(steps[0], p["shipping"]) and at(steps[1], p["inspection_zone_a"])
    assert steps[2]["docked"] == 1 and steps[1]["docked"] == 0
    # each step started only after the one before had ended
    assert steps[0]["ended_at"] <= steps[1]["started_at"] <= steps[1]["ended_at"]
    assert steps[1]["ended_at"] <= steps[2]["started_at"]
    # no goal of the mission was replaced by another
    assert not any("replaced" in e.message for e in gateway.events_since(0))


async def test_patrol_twice_is_four_trips_and_questions_read_the_stored_steps(store):
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("patrol between the assembly station and shipping twice")
    assert "4 steps" in result.answer
    assert agent.missions.wait(60)
    steps = store.mission_steps(result.mission_id)
    p = places(store)
    want = ["assembly_station", "shipping"] * 2
    assert all(at(s, p[name]) for s, name in zip(steps, want, strict=True)), steps
    answer = (await agent.turn("how far along is the mission?")).answer
    assert f"mission {result.mission_id} succeeded" in answer and "4. go to shipping" in answer
    assert answer.count("succeeded (arrived") == 4


async def test_a_condition_on_the_battery_skips_its_step_and_says_why(store):
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("if the battery is under 30 %, dock first, then go to cps storage")
    assert agent.missions.wait(60)
    first, second = store.mission_steps(result.mission_id)
    assert first["status"] == "skipped" and "not battery under 30 %" in first["detail"]
    assert second["status"] == "succeeded" and at(second, places(store)["cps_storage"])


async def test_a_place_that_does_not_exist_fails_its_step_and_ends_the_mission(store):
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("undock, then go to the moon, then dock")
    assert agent.missions.wait(60)
    m = view.as_json(store, result.mission_id)
    assert m["status"] == "failed" and "step 2 of 3 (go to moon) failed" in m["reason"]
    assert [s["status"] for s in m["steps"]] == ["succeeded", "failed", "pending"]
    assert "no location named 'moon'" in m["steps"][1]["detail"]


def test_the_e_stop_during_step_2_stops_the_mission_and_says_so(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    steps = [Step("undock"), Step("goto", place="shipping"), Step("dock")]
    mission_id = runner.start(steps, "test")
    wait_for_step(store, mission_id, 1)
    time.sleep(0.3)  # well under way to shipping
    gateway.estop()
    assert runner.wait(30)
    m = view.as_json(store, mission_id)
    assert m["status"] == "stopped"
    assert m["reason"].startswith("stopped by the E-STOP at step 2 of 3")
    assert [s["status"] for s in m["steps"]] == ["succeeded", "e-stopped", "pending"]
    assert not at(store.mission_steps(mission_id)[1], places(store)["shipping"])
    gateway.close()


def test_a_goal_replaced_by_another_is_replaced_never_succeeded(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    mission_id = runner.start([Step("undock"), Step("goto", place="shipping"), Step("dock")])
    wait_for_step(store, mission_id, 1)
    time.sleep(0.3)
    other = gateway.run(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'cps_storage'}\"",
        YES,
    )
    assert other.executed and not other.error
    assert runner.wait(30)
    step = store.mission_steps(mission_id)[1]
    assert step["status"] == "replaced" and "cps_storage" in step["detail"]
    assert store.mission(mission_id)["status"] == "failed"
    gateway.close()


def test_cancel_through_the_store_stops_the_robot_and_one_mission_at_a_time(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    mission_id = runner.start([Step("undock"), Step("goto", place="shipping")])
    with pytest.raises(MissionError, match="is running on this robot"):
        MissionRunner(gateway, store).start([Step("dock")])
    wait_for_step(store, mission_id, 1)
    assert store.request_mission_cancel(mission_id) == "running"  # as `astiop mission cancel`
    assert runner.wait(30)
    m = view.as_json(store, mission_id)
    assert m["status"] == "canceled" and "at step 2 of 2" in m["reason"]
    assert m["steps"][1]["status"] == "canceled"
    time.sleep(0.2)
    assert gateway.state().status.active_goal == ""
    assert gateway.state().state_word != "e_stopped", "a cancel does not latch the robot's stop"
    assert "canceled by the operator" in m["steps"][1]["detail"]
    after = MissionRunner(gateway, store)  # the robot was not left held: it moves again
    again = after.start([Step("goto", place="inspection_zone_a")])
    assert after.wait(60) and store.mission(again)["status"] == "succeeded"
    gateway.close()


def test_steps_round_trip_and_bad_steps_are_refused():
    step = Step("goto", xy=(3.0, 4.0), when=Condition("battery", "<", 30))
    assert Step.from_json(step.to_json()) == step
    for bad in ({"kind": "fly"}, {"kind": "goto"}, {"kind": "wait", "seconds": 0}):
        with pytest.raises(ValueError):
            Step(**bad)


KILLED_MID_MISSION = textwrap.dedent(
    """
    import sys, time
    from astiop.missions.runner import MissionRunner
    from astiop.missions.steps import Step
    from astiop.transports.simulator.backend import SimBackend
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.sim.simulator import Simulator
    from astiop.store import Store
    store = Store(sys.argv[1])
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store, realtime=True), SafetyPolicy())
    gateway.start()
    runner = MissionRunner(gateway, store)
    runner.start([Step("undock"), Step("goto", place="shipping"), Step("dock")], "killed")
    while store.mission_steps(1)[1]["status"] != "running":
        time.sleep(0.02)
    print("step 2 running", flush=True)
    time.sleep(60)
    """
)


def test_a_killed_process_leaves_the_mission_interrupted_and_it_resumes(tmp_path):
    path = tmp_path / "astiop.db"
    Store(path).close()
    proc = subprocess.Popen(
        [sys.executable, "-c", KILLED_MID_MISSION, str(path)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().strip() == "step 2 running"
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    store = Store(path)  # the next open sees the driving process gone
    m = view.as_json(store, 1)
    assert m["status"] == "interrupted" and m["step"] == 2
    assert [s["status"] for s in m["steps"]] == ["succeeded", "interrupted", "pending"]
    assert "interrupted: step 2 of 3 (go to shipping)" in view.summary(m)
    gateway = gateway_for(store)
    gateway.backend.sim.undock()
    gateway.backend.sim.run_goal(60)  # this robot left the dock too, as the killed one had
    runner = MissionRunner(gateway, store)
    assert runner.resume(1) == 1
    assert runner.wait(60)
    m = view.as_json(store, 1)
    assert m["status"] == "succeeded"
    assert [s["status"] for s in m["steps"]] == ["succeeded"] * 3
    with pytest.raises(MissionError, match="not interrupted"):
        runner.resume(1)
    store.close()


def test_the_cli_runs_a_mission_in_order_and_shows_it(tmp_path, monkeypatch):
    monkeypatch.setenv("ASTIOP_DB", str(tmp_path / "cli.db"))
    out = run_cli(
        "chat", "--model", "rules", "--yes", "go to shipping, then inspection zone a, then dock"
    )
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.startswith("✓")]
    assert [ln.split(":")[0] for ln in lines] == [
        "✓ step 1/3 go to shipping",
        "✓ step 2/3 go to inspection_zone_a",
        "✓ step 3/3 dock",
    ]
    assert "mission 1 succeeded: all 3 steps done" in out.stdout
    shown = run_cli("mission", "show", "1", "--json")
    assert '"status": "succeeded"' in shown.stdout
    for args, said in (
        (("mission", "show", "7"), "no mission 7"),
        (("mission", "cancel", "1"), "mission 1 is succeeded: nothing to cancel"),
        (("mission", "resume", "1", "--yes"), "not paused or interrupted"),
    ):
        bad = run_cli(*args)
        assert bad.returncode != 0 and said in bad.stderr and len(bad.stderr.splitlines()) == 1


GO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{{name: '{}'}}\""


@pytest.mark.parametrize("order", [("shipping", "cps_storage"), ("cps_storage", "shipping")])
async def test_a_models_plan_of_several_goals_is_a_mission_held_to_the_requests_order(store, order):
    from tests.scripted_llm import ScriptedLLM

    llm = ScriptedLLM("openai")
    try:
        import json

        llm.replies = [json.dumps({"commands": [GO.format(p) for p in order]}), "unused"]
        gateway = gateway_for(store)
        endpoint = open_endpoint(f"openai:scripted@{llm.url}")
        agent = Agent(gateway, endpoint, store, mode="command", confirm=YES, session="test")
        # a clause the plain reader cannot turn into a step: the model plans
        request = "go to shipping, then go to cps storage, then tell me a joke"
        result = await agent.turn(request)
    finally:
        llm.close()
    if order[0] == "shipping":
        assert result.answer.startswith(f"mission {result.mission_id} started: 2 steps")
        assert agent.missions.wait(60)
        steps = store.mission_steps(result.mission_id)
        assert [s["label"] for s in steps] == ["go to shipping", "go to cps_storage"]
        assert [s["status"] for s in steps] == ["succeeded", "succeeded"]
    else:  # out of the request's order: refused, nothing sent
        assert result.mission_id is None and "not the request's next step" in result.refused
        assert not any(c.executed for c in result.commands)
        assert gateway.backend.sim.goal is None


@pytest.mark.slow
async def test_mcp_start_mission_asks_once_for_every_step_and_reports_each(tmp_path):
    import json

    from tests.system.test_mcp import Console, call, stdio

    db = tmp_path / "mcp.db"
    Store(db).close()
    console = Console(db, [True])
    console.start()
    steps = [{"kind": "undock"}, {"kind": "goto", "place": "assembly_station"}, {"kind": "dock"}]
    try:
        async with stdio(db, "--approval-timeout", "10") as client:
            error, text = await call(client, "start_mission", {"steps": [{"kind": "fly"}]})
            assert error and text.startswith("step 1: kind must be one of")
            error, text = await call(
                client, "start_mission", {"steps": [{"kind": "goto", "place": "moon"}]}
            )
            assert error and text == "step 1: no location named moon"
            error, text = await call(client, "start_mission", {"steps": steps})
            assert not error and text.startswith("mission 1 started: 3 steps"), text
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                status = json.loads((await call(client, "mission_status"))[1])
                if status["status"] != "running":
                    break
                time.sleep(0.3)
            error, text = await call(client, "cancel_mission")
            assert error and text == "no mission is running"
    finally:
        console.done.set()
        console.join(5)
    assert status["status"] == "succeeded", status
    assert [s["status"] for s in status["steps"]] == ["succeeded"] * 3
    assert len(console.seen) == 1  # one approval, every step in it
    assert console.seen[0]["command"] == "mission: 1. undock; 2. go to assembly_station; 3. dock"


def test_a_dock_step_on_a_docked_robot_is_skipped_as_the_robot_reports_it(store):
    runner = MissionRunner(gateway_for(store), store)
    mission_id = runner.start([Step("dock"), Step("undock"), Step("undock")])
    assert runner.wait(30)
    steps = store.mission_steps(mission_id)
    assert [s["status"] for s in steps] == ["skipped", "succeeded", "skipped"]
    assert steps[0]["detail"] == "the robot reports it is docked already"
    assert store.mission(mission_id)["status"] == "succeeded"
