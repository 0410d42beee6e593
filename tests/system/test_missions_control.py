"""A mission's operator controls on the in-process simulator: a new mission replaces the running
one only when asked; a pause holds the robot at the end of the current step until resumed; a
repeat until stopped runs round after round until canceled; the session's recording holds the
mission's own record (start, each step's end with the pose, its end)."""

import math
import re
import time

import pytest

from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.missions import view
from astiop.missions.runner import MissionError, MissionRunner
from astiop.missions.steps import Step
from astiop.store import Store
from tests.cli_runner import run_cli
from tests.system.test_missions import at, gateway_for, places, wait_for_step

YES = lambda _c: True  # noqa: E731


def until(predicate, timeout_s=30.0, what=""):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"still not so after {timeout_s:g} s: {what}")
        time.sleep(0.02)


def status(store, mission_id):
    return store.mission(mission_id)["status"]


# -- replace ------------------------------------------------------------------------------
def test_a_new_mission_replaces_the_running_one_only_when_asked(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    first = runner.start([Step("undock"), Step("goto", place="shipping"), Step("dock")])
    wait_for_step(store, first, 1)
    with pytest.raises(MissionError, match=r"mission 1 is running on this robot \(step 2 of 3"):
        runner.start([Step("goto", place="cps_storage")])
    assert len(store.missions()) == 1, "a refused mission is not stored"
    # another runner, as another process: the replacement goes through the store
    other = MissionRunner(gateway, store)
    second = other.start([Step("goto", place="cps_storage")], replace=first)
    assert status(store, first) == "replaced", "ended before the new mission starts"
    m = view.as_json(store, first)
    assert m["reason"] == f"replaced by mission {second} at step 2 of 3 (go to shipping)"
    assert m["steps"][1]["status"] == "replaced"
    assert m["steps"][1]["detail"].startswith(f"replaced by mission {second} during 'go to ship")
    assert m["steps"][2]["status"] == "pending", "the replaced mission's next step never ran"
    assert other.wait(60) and status(store, second) == "succeeded"
    step = store.mission_steps(second)[0]
    assert step["started_at"] >= store.mission(first)["finished_at"]
    assert at(step, places(store)["cps_storage"])
    gateway.close()


async def test_a_chat_mission_while_one_runs_is_refused_unless_told_to_replace_it(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    first = agent.missions.start([Step("wait", seconds=30), Step("undock")], "wait, undock")
    result = await agent.turn("go to shipping, then dock")
    assert result.mission_id is None
    assert result.answer.startswith(
        "Mission not started: mission 1 is running on this robot (step 1 of 2 (wait 30 s), 0 done)"
    )
    assert "astiop chat --replace" in result.answer and "astiop mission cancel 1" in result.answer
    assert len(store.missions()) == 1 and gateway.backend.sim.goal is None
    agent.replace_mission = True  # astiop chat --replace
    result = await agent.turn("go to shipping, then dock")
    assert result.answer.startswith("mission 2 started: 2 steps"), result.answer
    assert result.answer.endswith("(it replaced mission 1)")
    assert status(store, first) == "replaced"
    assert store.mission(first)["reason"] == "replaced by mission 2 at step 1 of 2 (wait 30 s)"
    assert agent.missions.wait(60) and status(store, 2) == "succeeded"
    gateway.close()


# -- pause and resume ---------------------------------------------------------------------
def test_a_pause_holds_the_robot_at_the_end_of_the_current_step_until_resumed(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    notes = []
    runner = MissionRunner(gateway, store, on_note=notes.append)
    mid = runner.start([Step("undock"), Step("goto", place="shipping"), Step("dock")])
    wait_for_step(store, mid, 1)
    assert store.request_mission_pause(mid) == "running"  # as `astiop mission pause`
    asked = view.summary(view.as_json(store, mid))
    assert asked.endswith("pauses at the end of this step"), asked
    until(lambda: status(store, mid) == "paused", what="paused")
    steps = store.mission_steps(mid)
    assert steps[1]["status"] == "succeeded", "the step in progress ended as the robot reported"
    assert at(steps[1], places(store)["shipping"])
    time.sleep(1.5)  # held: the next step does not start
    assert store.mission_steps(mid)[2]["status"] == "pending"
    robot = gateway.state().status
    assert robot.active_goal == "" and not robot.docked
    m = view.as_json(store, mid)
    assert view.summary(m) == "mission 1 paused: before step 3 of 3 (dock), 2 done"
    assert store.request_mission_pause(mid, pause=False) == "paused"  # resume
    assert runner.wait(60) and status(store, mid) == "succeeded"
    assert store.mission_steps(mid)[2]["docked"] == 1
    assert notes == [
        "mission 1 paused before step 3 of 3 (dock)",
        "mission 1 goes on with step 3 of 3",
    ]
    gateway.close()


@pytest.mark.parametrize("how", ["e-stop", "cancel", "replace"])
def test_a_paused_mission_ends_on_the_e_stop_a_cancel_or_a_replacement(store, how):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    mid = runner.start([Step("wait", seconds=0.3), Step("undock")])
    store.request_mission_pause(mid)
    until(lambda: status(store, mid) == "paused", what="paused")
    if how == "e-stop":
        gateway.estop()
    elif how == "cancel":
        assert store.request_mission_cancel(mid) == "paused"
    else:
        MissionRunner(gateway, store).start([Step("wait", seconds=0.1)], replace=mid)
    assert runner.wait(30)
    row = store.mission(mid)
    said = {
        "e-stop": ("stopped", "stopped by the E-STOP"),
        "cancel": ("canceled", "canceled by the operator"),
        "replace": ("replaced", "replaced by mission 2"),
    }[how]
    assert (row["status"], row["reason"]) == (
        said[0],
        f"{said[1]} while paused before step 2 of 2 (undock)",
    )
    assert store.mission_steps(mid)[1]["status"] == "pending"
    assert gateway.state().status.docked, "the undock never ran"
    gateway.close()


# -- repeat until stopped -----------------------------------------------------------------
async def test_until_i_stop_it_repeats_round_after_round_until_canceled(store):
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("patrol between shipping and the assembly station until I stop it")
    assert result.answer == (
        "mission 1 started: 2 steps — 1. go to shipping; 2. go to assembly_station; "
        "repeated until stopped"
    )
    until(lambda: store.mission(1)["round"] >= 3, 60, "round 3")
    m = view.as_json(store, 1)
    assert m["until_stopped"] and m["steps_total"] == 2
    assert re.search(
        r"^mission 1 running: round \d+ \(until stopped\), step [12] of 2", view.summary(m)
    )
    assert store.request_mission_cancel(1) == "running"
    assert agent.missions.wait(30)
    m = view.as_json(store, 1)
    assert m["status"] == "canceled"
    found = re.search(r"at step [12] of 2 in round (\d+) .*; (\d+) rounds? done$", m["reason"])
    assert found and int(found[2]) == int(found[1]) - 1 >= 2, m["reason"]
    # each round went to both places: the goals the mission sent, in order
    goals = [
        c["command"]
        for c in store.db.query("SELECT command FROM commands WHERE source = 'mission' ORDER BY id")
        if "goto_position" in c["command"]
    ]
    rounds_done = int(found[2])
    want = ["shipping", "assembly_station"] * rounds_done
    assert [("shipping" if "shipping" in g else "assembly_station") for g in goals][
        : len(want)
    ] == want
    gateway.close()


def test_a_failed_step_ends_a_repeat_until_stopped_and_is_never_repeated(store):
    runner = MissionRunner(gateway_for(store), store)
    mid = runner.start([Step("goto", place="shipping"), Step("goto", place="moon")], forever=True)
    assert runner.wait(60)
    m = view.as_json(store, mid)
    assert m["status"] == "failed" and m["round"] == 1
    assert m["reason"].startswith("step 2 of 2 in round 1 (go to moon) failed: ")
    assert m["reason"].endswith("; 0 rounds done")


# -- the recording ------------------------------------------------------------------------
def test_the_recording_holds_the_missions_start_each_steps_end_and_its_end(store, tmp_path):
    from astiop.recording import SessionRecorder
    from astiop.recording.reader import Recording
    from astiop.transports.replay.backend import ReplayBackend

    gateway = gateway_for(store)
    path = tmp_path / "mission.mcap"
    recorder = SessionRecorder(path, gateway, store).start()
    runner = MissionRunner(gateway, store)
    mid = runner.start([Step("undock"), Step("goto", place="shipping"), Step("dock")], "three")
    assert runner.wait(60)
    time.sleep(0.6)  # the recorder's next look at the store
    recorder.stop()
    recording = Recording(path)
    ch = recording.channels["/astiop/mission"]
    records = [ch.message(i) for i in range(len(ch.times))]
    assert [r["event"] for r in records] == ["started"] + ["step_ended"] * 3 + ["ended"]
    assert records[0]["steps"] == ["undock", "go to shipping", "dock"]
    assert [(r["step"], r["status"]) for r in records[1:4]] == [
        (1, "succeeded"),
        (2, "succeeded"),
        (3, "succeeded"),
    ]
    pose = records[2]["pose"]
    assert math.dist((pose["x"], pose["y"]), places(store)["shipping"]) <= 0.3
    assert records[3]["docked"] is True
    assert records[-1] == {
        **records[-1],
        "mission": mid,
        "status": "succeeded",
        "reason": "all 3 steps done",
    }
    assert ch.times == sorted(ch.times)
    # a replay shows the mission's progress among the robot's events, as its clock reaches it
    replay = ReplayBackend(recording, paused=True)
    replay.playback.seek((ch.times[2] - recording.start_ns) / 1e9)
    said = [e.message for e in replay.events_since(0) if e.kind == "mission"]
    assert said == [r["text"] for r, t in zip(records, ch.times, strict=True) if t <= ch.times[2]]
    assert said[2].startswith("mission 1: ✓ step 2/3 go to shipping")
    replay.playback.seek(recording.duration_s)
    said = [e.message for e in replay.events_since(0) if e.kind == "mission"]
    assert said[0] == "mission 1 started: 3 steps — 1. undock; 2. go to shipping; 3. dock"
    assert said[2].startswith("mission 1: ✓ step 2/3 go to shipping: succeeded — arrived")
    assert said[-1] == "mission 1 succeeded: all 3 steps done"
    gateway.close()


# -- the CLI, on a mission this process drives ------------------------------------------------
def test_the_cli_pauses_resumes_and_replaces_a_mission_another_runner_drives(tmp_path, monkeypatch):
    db = tmp_path / "cli.db"
    monkeypatch.setenv("ASTIOP_DB", str(db))
    store = Store(db)
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    mid = runner.start([Step("wait", seconds=3), Step("wait", seconds=30), Step("undock")])
    out = run_cli("mission", "pause", str(mid))
    assert out.returncode == 0 and out.stdout == "mission 1: pauses at the end of step 1 of 3\n"
    until(lambda: status(store, mid) == "paused", what="paused")
    shown = run_cli("mission", "show", "1").stdout.splitlines()[0]
    assert shown == "mission 1 paused: before step 2 of 3 (wait 30 s), 1 done"
    assert run_cli("mission", "list").stdout.splitlines()[0] == shown
    again = run_cli("mission", "pause", "1")
    assert again.returncode != 0 and "is paused already" in again.stderr
    bad = run_cli("mission", "resume", "1", "--from", "1")
    assert bad.returncode != 0 and "--from resumes an interrupted mission only" in bad.stderr
    out = run_cli("mission", "resume", "1")
    assert out.returncode == 0 and out.stdout == "mission 1: resume asked of its process\n"
    wait_for_step(store, mid, 1)
    refused = run_cli("chat", "--model", "rules", "--yes", "go to shipping, then dock")
    assert "Mission not started: mission 1 is running on this robot" in refused.stdout
    assert "--replace" in refused.stdout and len(store.missions()) == 1
    replaced = run_cli(
        "chat", "--model", "rules", "--yes", "--replace", "go to shipping, then dock"
    )
    assert "mission 2 started: 2 steps" in replaced.stdout, replaced.stdout + replaced.stderr
    assert "mission 2 succeeded: all 2 steps done" in replaced.stdout
    assert runner.wait(30)
    row = store.mission(mid)
    assert (row["status"], row["reason"]) == (
        "replaced",
        "replaced by mission 2 at step 2 of 3 (wait 30 s)",
    )
    gateway.close()
    store.close()


def test_mcp_start_mission_replaces_only_with_replace_and_the_approval_says_so(tmp_path):
    from astiop.mcp.approval import Policy
    from astiop.mcp.tools import CALL, Call, Refused, RobotTools
    from tests.system.test_mcp import Console

    db = tmp_path / "mcp.db"
    store = Store(db)
    gateway = gateway_for(store, realtime=True, speed=20.0)
    console = Console(db, [True])
    console.start()
    until(store.console_open, what="the console's first heartbeat")
    robot = RobotTools(gateway, store, Policy(timeout_s=10))
    interaction = store.start_interaction(model="m", mode="mcp", prompt="start_mission")
    token = CALL.set(Call("pytest", "start_mission", interaction))
    try:
        runner = MissionRunner(gateway, store)
        first = runner.start([Step("wait", seconds=30), Step("undock")], "console's")
        with pytest.raises(Refused, match=r"mission 1 is running on this robot .*replace: true"):
            robot.start_mission([{"kind": "undock"}])
        assert console.seen == [] and len(store.missions()) == 1, "nothing asked or stored"
        text = robot.start_mission([{"kind": "undock"}], replace=True)
        assert text.startswith("mission 2 started: 1 step — 1. undock"), text
        assert text.endswith("It replaced mission 1.")
        assert runner.wait(30)
        assert robot._missions().wait(60) and status(store, 2) == "succeeded"
    finally:
        CALL.reset(token)
        console.done.set()
        console.join(5)
    assert len(console.seen) == 1
    asked = console.seen[0]
    said = "It replaces mission 1 (running: step 1 of 2 (wait 30 s), 0 done)"
    assert said in asked["detail"] and "replaces mission 1" in asked["command"]
    row = store.mission(first)
    assert (row["status"], row["reason"]) == (
        "replaced",
        "replaced by mission 2 at step 1 of 2 (wait 30 s)",
    )
    gateway.close()
    store.close()
