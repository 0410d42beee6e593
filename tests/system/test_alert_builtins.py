"""The built-in alerts a robot has without any watch: a goal aborted or cancelled by someone
else, no progress toward a goal, a mission failed or interrupted, the battery's threshold from
the robot's profile; each written once across processes on one database."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from astiop.config import Settings
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.state import Battery, Pose2D, RobotEvent, RobotState, Status
from astiop.watches.builtins import goal_end
from astiop.watches.evaluator import Evaluator
from astiop.watches.runner import make_evaluator


def _state(*, goal="", x=0.0, e_stopped=False, state="idle", battery=50.0) -> RobotState:
    status = Status(state if not goal else "navigating", "auto", goal, "", 0.0, False, False)
    return RobotState(
        0.0,
        pose=Pose2D(x, 0.0, 0.0),
        battery=Battery(battery / 100, 24.0, -1.0, False),
        status=status,
        plan=((x, 0.0), (10.0, 0.0)) if goal else (),
        e_stopped=e_stopped,
    )


def _goal(seq: int, message: str) -> RobotEvent:
    return RobotEvent(seq, 0.0, "goal", "warning", message)


def kinds(alerts):
    return [a["kind"] for a in alerts]


def test_each_transports_words_for_a_goals_end_are_read():
    assert goal_end(_goal(1, "goal 3 aborted: path blocked for 30 s")) == (
        "aborted",
        "path blocked for 30 s",
        "3",
    )
    assert goal_end(_goal(1, "goal finished: ABORTED (no valid path)")) == (
        "aborted",
        "no valid path",
        "",
    )
    assert goal_end(_goal(1, "goal canceled")) == ("canceled", "", "")
    assert goal_end(_goal(1, "goal finished: SUCCEEDED")) is None
    assert goal_end(_goal(1, "goal 2 accepted: dock")) is None
    assert goal_end(RobotEvent(1, 0.0, "nav", "info", "goal 3 aborted: x")) is None


def test_a_goal_aborted_or_cancelled_by_someone_else_is_an_alert(store):
    ev = Evaluator(store)
    fired = ev.step(_state(), now=0, events=[_goal(1, "goal 3 aborted: path blocked for 30 s")])
    assert kinds(fired) == ["goal_aborted"]
    assert fired[0]["message"] == "goal aborted: path blocked for 30 s"
    # the same goal's end said again (another process's simulator numbering alike): once
    assert ev.step(_state(), now=1, events=[_goal(2, "goal 3 aborted: path blocked")]) == []
    other = ev.step(
        _state(), now=2, events=[_goal(3, "goal 4 canceled: canceled by the action client")]
    )
    assert kinds(other) == ["goal_canceled"]
    assert other[0]["message"] == "goal cancelled by someone else: canceled by the action client"


def test_the_operators_own_cancel_is_no_alert(store):
    ev = Evaluator(store)
    said = [
        _goal(1, "goal 5 canceled: replaced by a new goal: dock"),
        _goal(2, "goal 6 canceled: canceled by the operator"),
    ]
    assert ev.step(_state(), now=0, events=said) == []
    estop = ev.step(_state(e_stopped=True), now=1, events=[_goal(3, "goal canceled")])
    assert kinds(estop) == ["estop"]  # the E-STOP cancelled it: said as the E-STOP
    ev.step(_state(), now=1.5)
    store.add_command(None, command="stop", valid=1, executed=1)  # a stop, journaled just now
    assert ev.step(_state(), now=2, events=[_goal(4, "goal finished: CANCELED")]) == []


def test_no_progress_toward_a_goal_for_n_s_and_again_after_progress(store):
    ev = Evaluator(store, no_progress_s=10)
    assert ev.step(_state(goal="shipping", x=0.0), now=0) == []
    assert ev.step(_state(goal="shipping", x=0.05), now=9) == []  # 5 cm: no progress
    stuck = ev.step(_state(goal="shipping", x=0.05), now=10)
    assert kinds(stuck) == ["no_progress"]
    assert stuck[0]["message"] == "no progress toward shipping for 10 s"
    assert ev.step(_state(goal="shipping", x=0.05), now=30) == []  # said once
    assert ev.step(_state(goal="shipping", x=1.0), now=31) == []  # moving again: cleared
    assert kinds(ev.step(_state(goal="shipping", x=1.0), now=41)) == ["no_progress"]
    assert ev.step(_state(), now=42) == []  # no goal, nothing to progress toward


def test_no_progress_is_not_said_while_the_estop_holds(store):
    ev = Evaluator(store, no_progress_s=5)
    ev.step(_state(goal="dock"), now=0)
    assert kinds(ev.step(_state(goal="dock", e_stopped=True), now=6)) == ["estop"]


def test_a_mission_that_fails_or_is_interrupted_is_an_alert_once(store):
    done = store.create_mission("sim", "old", "chat", [("{}", "go")])
    store.finish_mission(done, "failed", "before this console")  # ended before: not said
    ev = Evaluator(store, mission_robot="sim")
    assert ev.step(_state(), now=0) == []
    mission = store.create_mission("sim", "go to shipping", "chat", [("{}", "go")])
    store.finish_mission(mission, "failed", "the goal was aborted")
    ev.builtin._missions_at = -1e9  # read the missions again now
    fired = ev.step(_state(), now=1)
    assert kinds(fired) == ["mission_failed"]
    assert fired[0]["message"] == f"mission {mission} failed: the goal was aborted"
    ev.builtin._missions_at = -1e9
    assert ev.step(_state(), now=2) == []
    other = store.create_mission("other_robot", "patrol", "chat", [("{}", "go")])
    store.finish_mission(other, "failed", "not this robot's")
    ev.builtin._missions_at = -1e9
    assert ev.step(_state(), now=3) == []


def test_the_battery_threshold_comes_from_the_profile_unless_the_settings_say(store):
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store), SafetyPolicy())
    assert gateway.profile is not None and gateway.profile.limits.battery_low == 20
    ev = make_evaluator(gateway, store, Settings())
    assert ev.step(_state(battery=21), now=0) == []
    assert kinds(ev.step(_state(battery=19.5), now=1)) == ["battery_low"]
    mine = make_evaluator(gateway, store, Settings(watches={"battery_low": 35}), robot="r2")
    assert kinds(mine.step(_state(battery=30), now=0)) == ["battery_low"]


TWIN = textwrap.dedent(
    """
    import sys, time
    from astiop.store import Store
    from astiop.transports.state import Battery, Pose2D, RobotEvent, RobotState, Status
    from astiop.watches.evaluator import Evaluator

    store = Store(sys.argv[1])
    ev = Evaluator(store, no_progress_s=0.2, mission_robot="sim")
    start = float(sys.argv[2])
    while time.time() < start:
        time.sleep(0.001)
    def st(goal, battery, e_stopped=False, x=0.0):
        status = Status("navigating" if goal else "idle", "", goal, "", 0.0, False, False)
        return RobotState(0.0, pose=Pose2D(x, 0, 0), battery=Battery(battery, 24, -1, False),
                          status=status, plan=((x, 0), (9, 0)) if goal else (),
                          e_stopped=e_stopped)
    aborted = RobotEvent(7, 0.0, "goal", "warning", "goal 9 aborted: path blocked")
    t = 0.0
    for i in range(40):
        time.sleep(0.05)
        t += 0.05
        ev.step(st("shipping", 0.15 if i > 5 else 0.5), now=t, events=[aborted] if i == 3 else [])
    ev.step(st("", 0.15, e_stopped=True), now=t + 1)
    store.close()
    """
)


def test_two_processes_on_one_database_write_each_built_in_alert_once(tmp_path):
    db = tmp_path / "twins.db"
    Store(db).close()
    import time

    start = f"{time.time() + 2.0:.3f}"  # both step through the same readings at the same time
    procs = [
        subprocess.Popen([sys.executable, "-c", TWIN, str(db), start], stderr=subprocess.PIPE)
        for _ in range(2)
    ]
    for p in procs:
        _, err = p.communicate(timeout=60)
        assert p.returncode == 0, err.decode()
    store = Store(db)
    try:
        written = sorted(kinds(store.list_alerts()))
    finally:
        store.close()
    assert written == ["battery_low", "estop", "goal_aborted", "no_progress"]


def test_a_robot_blocked_during_a_goal_raises_no_progress_then_goal_aborted(store):
    """On the simulator: a pallet and two forklifts close the room; the goal behind them."""
    import math

    from tests.system.test_sim import ROOM

    sim = Simulator(ROOM, start=(2.0, 5.0, 0.0), seed=2, blocked_give_up_s=20.0)
    for kind, y in (("forklift", 3.0), ("forklift", 7.0), ("pallet", 5.0)):
        sim.add_obstacle(kind, 5.0, y, math.pi / 2)
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy())
    ev = Evaluator(store, no_progress_s=5.0)
    sim.goto(8.0, 5.0, 0.0, "behind the pallet")
    seen, seq, blocked_at = [], 0, None
    while sim.t < 60 and "goal_aborted" not in kinds(seen):
        sim.step(0.1)
        state, events = gateway.state(), gateway.events_since(seq)
        seq = events[-1].seq if events else seq
        if blocked_at is None and state.status.state == "blocked":
            blocked_at = state.t
        for a in ev.step(state, now=state.t, events=events):
            seen.append({**a, "t": state.t})
    assert kinds(seen) == ["no_progress", "goal_aborted"]
    stuck, aborted = seen
    assert stuck["message"].startswith("no progress toward behind the pallet for 5 s")
    assert blocked_at is not None and stuck["t"] - blocked_at <= 5.5  # it stopped before blocked
    assert aborted["message"] == "goal aborted: path blocked for 20 s"


def test_another_clients_nav2_goal_that_aborts_is_said_once_and_ours_is_not():
    """As the action server's status topic lists them (action_msgs/msg/GoalStatus: 2
    EXECUTING, 4 SUCCEEDED, 5 CANCELED, 6 ABORTED)."""
    from astiop.transports.event_log import EventLog
    from astiop.transports.goal_ends import GoalEnds

    events = EventLog(0.0)
    ends = GoalEnds(events)
    ends.sent.append("ffff0000" * 4)  # a goal this process sent: said with its result
    ends.listed([("aaaa1111" * 4, 2), ("ffff0000" * 4, 2), ("bbbb2222" * 4, 2)])
    ends.listed([("aaaa1111" * 4, 6), ("ffff0000" * 4, 6), ("bbbb2222" * 4, 4)])
    ends.listed([("aaaa1111" * 4, 6), ("cccc3333" * 4, 5)])  # listed again; never seen running
    said = [e.message for e in events.since(0)]
    assert said == ["goal aaaa1111 aborted (another client's goal)"]
    assert goal_end(events.since(0)[0]) == ("aborted", "another client's goal", "aaaa1111")


def test_a_goal_number_said_again_later_is_another_goal(store, monkeypatch):
    """A simulator numbers its goals anew in each run: goal 3 aborted a while after an earlier
    goal 3 aborted is a new alert, not the old one said again."""
    import astiop.store.watches as store_watches

    ev = Evaluator(store)
    assert kinds(ev.step(_state(), now=0, events=[_goal(1, "goal 3 aborted: blocked")])) == [
        "goal_aborted"
    ]
    monkeypatch.setattr(store_watches, "SETTLE_S", 0.0)  # the first alert is old enough now
    again = ev.step(_state(), now=1, events=[_goal(2, "goal 3 aborted: blocked again")])
    assert kinds(again) == ["goal_aborted"] and again[0]["message"].endswith("blocked again")
