"""Missions against what a hostile review tried: the driver killed and an immediate resume, a
resume refused (the mission stays resumable), a place removed mid-mission, requests longer than
a mission holds, and ids and counts too large for anything."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from astiop.agent.mission_plan import STEP_CAP, TooManySteps, steps_for
from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.config import load_settings
from astiop.missions import view
from astiop.missions.runner import MissionRunner
from astiop.missions.steps import Step
from astiop.robot.factory import make_sim_gateway
from astiop.robot.lease import Lease
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.store.leases import LEASE_TTL_S
from tests.cli_runner import run_cli
from tests.ros import until
from tests.system.test_missions import at, gateway_for, places, wait_for_step

YES = lambda _c: True  # noqa: E731
PLACES = {"shipping": (0.0, 0.0), "inspection_zone_a": (1.0, 0.0), "assembly_station": (2.0, 0.0)}

HOLDS_THE_LEASE = textwrap.dedent(
    """
    import sys, time
    from astiop.robot.lease import Lease
    from astiop.store import Store
    lease = Lease(Store(sys.argv[1]), "/@0", "the robot", "astiop")
    assert lease.take() is None
    print("held", flush=True)
    time.sleep(60)
    """
)


def test_a_killed_holders_lease_is_free_at_once(tmp_path):
    path = tmp_path / "a.db"
    Store(path).close()
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLDS_THE_LEASE, str(path)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert proc.stdout.readline().strip() == "held"
        store = Store(path)
        mine = Lease(store, "/@0", "the robot", "mission resume")
        refused = mine.take()
        assert refused is not None and refused.pid == proc.pid, "a live holder keeps it"
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    try:
        # its process gone and a heartbeat missed: free well before the lease's time is out
        assert until(lambda: store.lease("/@0") is None, LEASE_TTL_S * 2)
        seen_at = store.db.conn.execute("SELECT seen_at FROM leases").fetchone()[0]
        assert time.time() - seen_at < LEASE_TTL_S, "not by waiting out the lease's time"
        assert mine.take() is None
    finally:
        mine.release()
        store.close()


def test_a_refused_resume_leaves_the_mission_resumable(tmp_path):
    store = Store(tmp_path / "b.db")
    gateway = make_sim_gateway(load_settings({}, env={}), store, sim=Simulator(seed=0))
    gateway.lease = Lease(store, "/@0", "the robot", "mission resume")
    other = Lease(Store(tmp_path / "b.db"), "/@0", "the robot", "someone else")
    queued = MissionRunner(gateway, store)
    queued.queue_only = True
    mission_id = queued.start([Step("undock"), Step("dock")], "test")
    try:
        assert other.take() is None
        runner = MissionRunner(gateway, store)
        assert runner.resume(mission_id) == 0
        assert runner.wait(30)
        m = view.as_json(store, mission_id)
        assert m["status"] == "interrupted", m
        assert m["reason"].startswith("resume refused at step 1 (undock): the robot is controlled")
        assert "nothing was sent" in m["reason"]
        assert gateway.state().status.docked, "nothing reached the robot"
        other.release()
        assert runner.resume(mission_id) == 0, "resumed again once the robot is free"
        assert runner.wait(60)
        assert view.as_json(store, mission_id)["status"] == "succeeded"
    finally:
        gateway.close()
        other.store.close()
        store.close()


def test_a_place_removed_during_the_mission_fails_its_step_with_nothing_sent(store):
    gateway = gateway_for(store, realtime=True, speed=20.0)
    runner = MissionRunner(gateway, store)
    steps = [Step("goto", place="shipping"), Step("goto", place="assembly_station")]
    mission_id = runner.start(steps, "go to shipping, then assembly station")
    wait_for_step(store, mission_id, 0)
    store.remove_location("assembly_station")
    assert runner.wait(60)
    m = view.as_json(store, mission_id)
    assert m["status"] == "failed", m
    assert m["steps"][1]["detail"] == (
        "the place 'assembly_station' was removed from this map's locations during the mission: "
        "nothing was sent"
    )
    assert at(store.mission_steps(mission_id)[1], places(store)["shipping"]), "it stayed there"
    gateway.close()


@pytest.mark.parametrize(
    "request_text,count",
    [
        (", then ".join(["go to shipping, then inspection zone a"] * 22), 44),
        ("patrol between shipping and inspection zone a 21 times", 42),
        ("go to shipping, then inspection zone a 100000000 times", 100000001),
        ("go to shipping, then inspection zone a 99999999999999999999999 times", None),
    ],
)
def test_a_request_longer_than_a_mission_says_so_and_builds_nothing(request_text, count):
    with pytest.raises(TooManySteps) as refused:
        steps_for(request_text, PLACES)
    assert refused.value.count == count
    has = f"{count} steps" if count else "more steps than can be counted"
    assert str(refused.value).startswith(f"this request has {has}; a mission holds at most 40")
    patrol = "patrol between shipping and inspection zone a 20 times"
    assert len(steps_for(patrol, PLACES)) == STEP_CAP, "the cap itself is a mission"


async def test_chat_says_the_step_cap_and_sends_nothing(store):
    gateway = gateway_for(store)
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=YES, session="test")
    result = await agent.turn("patrol between shipping and inspection zone a 22 times")
    assert result.answer == (
        "I did not start this mission: this request has 44 steps; a mission holds at most 40: "
        "nothing was sent (split it, or repeat it until stopped)."
    )
    assert result.commands == [] and store.latest_mission() is None


@pytest.mark.parametrize(
    "args",
    [
        ("show", "99999999999999999999"),
        ("cancel", "99999999999999999999"),
        ("show", "0"),
        ("resume", "1", "--from", "0", "--yes"),
    ],
)
def test_mission_ids_and_steps_out_of_range_are_refused_in_one_line(tmp_path, args):
    out = run_cli("--db", str(tmp_path / "c.db"), "mission", *args)
    assert out.returncode == 2, out
    assert len(out.stderr.strip().splitlines()) == 1 and "Invalid value" in out.stderr, out
