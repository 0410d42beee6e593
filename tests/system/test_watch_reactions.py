"""A watch whose reaction moves the robot: mission steps approved when the watch is made, run
once by the process that wrote the alert, refused while the E-STOP holds."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from astiop.missions.steps import Step
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from astiop.watches.evaluator import Evaluator
from astiop.watches.model import Watch, WatchError, validate
from astiop.watches.reactions import mission_reaction
from astiop.watches.runner import Watching


def run_cli(*args: str, input: str = ""):
    """The CLI in a process of its own: the approval is asked on its terminal (stdin)."""
    cmd = [sys.executable, "-m", "astiop", *args]
    return subprocess.run(cmd, input=input, capture_output=True, text=True, timeout=120)


def _watching(store) -> tuple[RobotGateway, Watching]:
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store), SafetyPolicy(), store=store)
    return gateway, Watching(gateway, Evaluator(store, builtins=False))


def _undock_when_below_90(store) -> int:
    reaction = mission_reaction([Step("undock")], "ana on bench")
    watch = validate(Watch("battery", "<", 90, reaction=reaction))  # the simulator is at 85 %
    return store.add_watch(**watch.row())


def test_a_moving_reaction_is_refused_while_the_estop_holds_and_fires_no_more(store):
    wid = _undock_when_below_90(store)
    gateway, watching = _watching(store)
    gateway.estop()
    (alert,) = watching.step(gateway.state())
    assert alert["watch_id"] == wid
    assert alert["reaction"] == (f"watch {wid}: reaction not run: the E-STOP holds (1. undock)")
    assert store.missions() == []  # nothing was sent
    assert store.watch(wid)["armed"] == 0  # once: armed again only by hand
    watching.evaluator.reload()
    assert watching.step(gateway.state()) == []
    assert gateway.backend.sim.docked()  # the robot did not move


def test_a_moving_reaction_starts_its_mission_once(store):
    wid = _undock_when_below_90(store)
    gateway, watching = _watching(store)
    (alert,) = watching.step(gateway.state())
    (mission,) = store.missions()
    assert alert["reaction"] == f"watch {wid}: mission {mission['id']} started (1. undock)"
    assert mission["source"] == "watch" and mission["request"].startswith(f"watch {wid}: ")
    assert watching.step(gateway.state()) == []
    assert len(store.missions()) == 1


def test_a_moving_reaction_fires_once_and_is_approved_steps():
    reaction = mission_reaction([Step("goto", place="shipping")], "ana")
    try:
        validate(Watch("battery", "<", 20, repeat="every", reaction=reaction))
    except WatchError as exc:
        assert "fires once" in str(exc)
    else:
        raise AssertionError("a moving reaction that fires every time was kept")
    unapproved = json.dumps({"steps": [Step("dock").to_json()], "approved_by": ""})
    try:
        validate(Watch("battery", "<", 20, reaction=unapproved))
    except WatchError as exc:
        assert "approved" in str(exc)
    else:
        raise AssertionError("an unapproved reaction was kept")


def test_watch_add_then_asks_for_approval_and_keeps_the_steps(tmp_path):
    db = str(tmp_path / "w.db")
    said = ["--db", db, "watch", "add", "tell me when the battery is below 20 %"]
    refused = run_cli(*said, "--then", "dock", input="n\n")
    assert refused.returncode != 0 and "not approved; nothing was stored" in refused.stderr
    nowhere = run_cli(*said, "--then", "atlantis", "--yes")
    assert nowhere.returncode != 0 and "no place called 'atlantis'" in nowhere.stderr
    kept = run_cli(*said, "--then", "shipping", "--then", "dock", input="y\n")
    assert kept.returncode == 0, kept.stderr
    assert "the robot will: 1. go to shipping; 2. dock (once). Arm it?" in kept.stderr
    assert kept.stdout.strip() == (
        "watch 1: I will tell you when the battery is below 20 % (once), "
        "then 1. go to shipping; 2. dock"
    )
    store = Store(tmp_path / "w.db")
    try:
        reaction = json.loads(store.watch(1)["reaction"])
    finally:
        store.close()
    assert reaction["approved_by"].endswith("(astiop watch add)")


def test_watch_add_reads_a_reaction_said_in_words(tmp_path):
    db = str(tmp_path / "w.db")
    said = "tell me when the robot reaches shipping, then send it to the dock"
    kept = run_cli("--db", db, "watch", "add", said, input="y\n")
    assert kept.returncode == 0, kept.stderr
    assert "the robot will: 1. dock (once). Arm it?" in kept.stderr
    assert kept.stdout.strip().endswith("(once), then 1. dock")
    both = run_cli("--db", db, "watch", "add", said, "--then", "dock", "--yes")
    assert both.returncode != 0 and "in words or with --then, not both" in both.stderr
    idle = run_cli("--db", db, "watch", "add", said.replace("send it to the dock", "wave"))
    assert idle.returncode != 0 and "not 'wave'; nothing was stored" in idle.stderr


@pytest.mark.parametrize("held_before", [False, True], ids=["free", "held"])
def test_control_a_reaction_took_of_a_free_robot_is_let_go_of_when_its_mission_ends(
    store, held_before
):
    """A headless watcher (serve's `watch run`) that runs a reaction on a robot no one held does
    not keep it from every operator afterwards; a process that held it before keeps it."""
    from astiop.robot.lease import Lease
    from tests.ros import until

    wid = _undock_when_below_90(store)
    gateway, watching = _watching(store)
    gateway.lease = lease = Lease(store, "/@0", "the robot", "astiop watch run")
    try:
        if held_before:
            assert gateway.take_control() is None
        (alert,) = watching.step(gateway.state())
        assert alert["reaction"].startswith(f"watch {wid}: mission ")
        assert until(lambda: store.missions()[0]["status"] == "succeeded", 60)
        if held_before:
            assert not until(lambda: not lease.held, 2)
            assert store.lease("/@0")["token"] == lease.token
        else:
            assert until(lambda: not lease.held and store.lease("/@0") is None, 10)
    finally:
        gateway.close()
