"""Watches and built-in alerts, evaluated against robot states on a real SQLite store."""

from __future__ import annotations

import pytest

from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.state import Battery, RobotState, Status
from astiop.watches.evaluator import Evaluator
from astiop.watches.model import Watch, WatchError, validate
from astiop.watches.words import watch_from_words


def _state(battery=None, *, fault="", lost_s=None, e_stopped=False, t=0.0) -> RobotState:
    bat = None if battery is None else Battery(battery / 100, 24.0, -1.0, False)
    status = Status("idle", "auto", "", fault, 0.0, False, False)
    return RobotState(t, battery=bat, status=status, e_stopped=e_stopped, lost_s=lost_s)


def _add(store, watch: Watch) -> int:
    return store.add_watch(**validate(watch).row())


def kinds(alerts):
    return [a["kind"] for a in alerts]


def test_a_battery_watch_fires_once_when_the_battery_crosses_its_threshold(store):
    wid = _add(store, Watch("battery", "<", 30))
    ev = Evaluator(store, builtins=False)
    assert ev.step(_state(35), now=0) == []
    fired = ev.step(_state(29.5), now=1)
    assert kinds(fired) == ["watch"] and fired[0]["watch_id"] == wid
    assert fired[0]["reading"] == "29.50 %" and "below 30 %" in fired[0]["message"]
    assert ev.step(_state(29), now=2) == []
    assert ev.step(_state(40), now=3) == [] and ev.step(_state(20), now=4) == []  # once: done
    assert store.watch(wid)["armed"] == 0
    assert len(store.list_alerts()) == 1


def test_an_every_time_watch_fires_each_time_the_condition_comes_back(store):
    _add(store, Watch("battery", "<", 30, repeat="every"))
    ev = Evaluator(store, builtins=False)
    readings = [35, 29, 28, 29.5, 30.5, 31.5, 29, 35, 25]  # 30.5 is inside the 1 % margin
    fired = [len(ev.step(_state(b), now=i)) for i, b in enumerate(readings)]
    assert fired == [0, 1, 0, 0, 0, 0, 1, 0, 1]


def test_a_watch_held_for_a_duration_fires_only_once_it_has_held_that_long(store):
    _add(store, Watch("battery", "<", 30, duration_s=5))
    ev = Evaluator(store, builtins=False)
    assert ev.step(_state(29), now=0) == [] and ev.step(_state(29), now=4) == []
    assert ev.step(_state(31.5), now=4.5) == []  # cleared: the time starts again
    assert ev.step(_state(29), now=5) == [] and ev.step(_state(29), now=9.9) == []
    assert kinds(ev.step(_state(29), now=10)) == ["watch"]


def test_built_in_alerts_battery_low_fault_contact_and_estop(store):
    store.latch_estop("operator ana")
    ev = Evaluator(store, battery_low=20)
    assert ev.step(_state(50), now=0) == []
    assert kinds(ev.step(_state(19), now=1)) == ["battery_low"]
    assert kinds(ev.step(_state(19, fault="left motor overcurrent"), now=2)) == ["fault"]
    assert kinds(ev.step(_state(19, lost_s=3.0), now=3)) == ["contact_lost"]
    assert kinds(ev.step(_state(19), now=4)) == ["contact_regained"]
    estop = ev.step(_state(19, e_stopped=True), now=5)
    assert kinds(estop) == ["estop"] and estop[0]["message"] == "E-STOP engaged by operator ana"
    assert ev.step(_state(19, e_stopped=True), now=6) == []


def test_two_evaluators_on_one_database_write_one_alert_per_event(tmp_path):
    a, b = Store(tmp_path / "w.db"), Store(tmp_path / "w.db")
    _add(a, Watch("battery", "<", 30, repeat="every"))
    first, second = Evaluator(a), Evaluator(b)
    for now, level in enumerate([40, 25, 40, 25]):
        first.step(_state(level), now=now)
        second.step(_state(level), now=now)
    assert kinds(a.list_alerts()) == ["watch", "watch"]  # two events, each written once
    a.close()
    b.close()


def test_the_operators_words_become_a_typed_watch_or_a_one_line_reason():
    w = watch_from_words("tell me when the battery is below 20 %")
    assert (w.field, w.op, w.threshold, w.repeat) == ("battery", "<", 20, "once")
    w = watch_from_words("alert me if the battery drops under 30 percent")
    assert (w.field, w.threshold) == ("battery", 30)
    w = watch_from_words("warn me if anything comes within 50 cm for 2 s")
    assert (w.field, w.op, w.threshold, w.duration_s) == ("obstacle_distance", "<", 0.5, 2)
    for not_a_watch in (
        "what is the battery level?",
        "tell me the battery",
        "go to shipping",
    ):
        assert watch_from_words(not_a_watch) is None, not_a_watch
    with pytest.raises(WatchError, match="in %, not 'm'"):
        watch_from_words("tell me when the battery is below 20 m")
    with pytest.raises(WatchError, match="between 0 and 100"):
        validate(watch_from_words("tell me when the battery is below 120 %"))


class _RobotWithout:
    """The roles of a robot that has no battery topic."""

    def has(self, role: str) -> bool:
        return role != "battery"


def test_a_watch_on_a_reading_the_robot_lacks_is_refused():
    with pytest.raises(WatchError, match="no battery"):
        validate(watch_from_words("tell me when the battery is below 20 %"), _RobotWithout())


async def test_the_agent_keeps_a_watch_said_in_plain_language_and_says_it_in_one_sentence(store):
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store), SafetyPolicy())
    agent = Agent(gateway, open_endpoint("rules"), store, session="test")
    result = await agent.turn("Tell me when the battery is below 20 %")
    assert result.answer == "Watch 1: I will tell you when the battery is below 20 % (once)."
    assert result.commands == []  # nothing was read or sent
    (row,) = store.list_watches()
    assert (row["field"], row["op"], row["threshold"], row["armed"]) == ("battery", "<", 20, 1)
    result = await agent.turn("alert me if the battery drops under 30 volts")
    assert result.answer.startswith("Not watched: the battery is measured in %, not 'volts'")
    assert len(store.list_watches()) == 1  # nothing stored
    result = await agent.turn("what is the battery level?")  # a question, as before
    assert "%" in result.answer and result.commands and len(store.list_watches()) == 1


WATCHES = {  # said -> (field, op, threshold, held s, once or every)
    "tell me when the battery is below 20 %": ("battery", "<", 20, 0, "once"),
    "Tell me when the battery is below 20%.": ("battery", "<", 20, 0, "once"),
    "alert me if the battery drops under 30 percent": ("battery", "<", 30, 0, "once"),
    "let me know when the battery level falls below 15": ("battery", "<", 15, 0, "once"),
    "please notify me if the battery goes under 25 % for 10 s": ("battery", "<", 25, 10, "once"),
    "can you tell me when the battery is above 95 %": ("battery", ">", 95, 0, "once"),
    "warn me whenever the battery is less than 40 per cent": ("battery", "<", 40, 0, "every"),
    "tell me every time the battery is under 20% for 1 minute": ("battery", "<", 20, 60, "every"),
    "warn me if anything comes within 0.5 m": ("obstacle_distance", "<", 0.5, 0, "once"),
    "warn me if an obstacle is within 50 cm for 2 seconds": (
        "obstacle_distance",
        "<",
        0.5,
        2,
        "once",
    ),
    "alert me if someone gets closer than 1 metre": ("obstacle_distance", "<", 1, 0, "once"),
    "tell me whenever the speed goes above 0.3 m/s": ("speed", ">", 0.3, 0, "every"),
    "let me know if the robot moves faster than 0.5 m/s": ("speed", ">", 0.5, 0, "once"),
    "tell me if the speed is below 0.05 m/s for 30 s": ("speed", "<", 0.05, 30, "once"),
}
NOT_WATCHES = (
    "what is the battery level?",
    "tell me the battery",
    "Can you tell me if it's charging?",
    "Visit zone B and tell me if anything is blocking.",
    "go to shipping",
    "is anything within 0.5 m?",
    "how fast is the robot going?",
)


@pytest.mark.parametrize("said", sorted(WATCHES))
def test_what_is_said_as_a_watch_becomes_that_watch(said):
    w = validate(watch_from_words(said))
    got = (w.field, w.op, w.threshold, w.duration_s, w.repeat)
    assert got == WATCHES[said]


@pytest.mark.parametrize("said", NOT_WATCHES)
def test_requests_that_are_no_watch_are_planned_as_before(said):
    assert watch_from_words(said) is None


PLACES = {"shipping": (37.6, 4.0), "charging_dock": (2.5, 3.0)}


def test_a_place_watch_is_read_with_the_places_coordinates_and_a_named_robot():
    w = watch_from_words(
        "let me know when astibot_2 reaches shipping", "", PLACES, None, ("astibot_2",)
    )
    assert (w.field, w.place, w.x, w.y, w.robot, w.op) == (
        "place",
        "shipping",
        37.6,
        4.0,
        "astibot_2",
        "<=",
    )
    assert w.sentence() == "astibot_2 is at shipping (within 0.3 m) (once)"
    assert (
        watch_from_words("tell me when the robot gets to the dock", "", PLACES).place
        == "charging_dock"
    )
    with pytest.raises(WatchError, match="no place called 'packing'"):
        watch_from_words("tell me when it arrives at packing", "", PLACES)
    with pytest.raises(WatchError, match="no robot named 'astibot_9'"):
        watch_from_words(
            "let me know when astibot_9 reaches shipping", "", PLACES, None, ("astibot_2",)
        )


def test_no_progress_and_conveyor_watches_and_what_stays_a_question():
    w = watch_from_words("alert me if the robot has not moved for 30 s during a goal")
    assert (w.field, w.op, w.threshold, w.duration_s) == ("no_progress", ">=", 30.0, 0.0)
    assert watch_from_words("warn me if it is stuck for a minute").threshold == 60.0
    c = watch_from_words("tell me when the conveyor is loaded")
    assert (c.field, c.op, c.threshold) == ("conveyor", ">=", 1.0)
    assert watch_from_words("tell me if the conveyor is loaded") is None  # asked, not watched
    with pytest.raises(WatchError, match="approved when the watch is made"):
        watch_from_words("tell me when the battery is below 20 %, then send it to the dock")


def test_a_reaction_is_split_from_its_watch_and_read_as_mission_steps():
    from astiop.agent.watch_turn import steps_from_words
    from astiop.missions.steps import Step
    from astiop.watches.words import split_reaction

    said = "tell me when the battery is below 20 %, then send it to the dock."
    assert split_reaction(said) == ("tell me when the battery is below 20 %", "send it to the dock")
    assert split_reaction("alert me if it is stuck for a minute, send it to shipping") == (
        "alert me if it is stuck for a minute", "send it to shipping",
    )  # fmt: skip
    assert split_reaction("go to shipping and then dock") == ("go to shipping and then dock", "")
    strengthen = "tell me when it reaches the strengthen bay"  # "then" inside a word
    assert split_reaction(strengthen) == (strengthen, "")
    assert split_reaction("tell me when the battery is below 20 %") == (
        "tell me when the battery is below 20 %", "",
    )  # fmt: skip
    places = dict(PLACES)
    assert steps_from_words("send it to shipping and then dock", places) == [
        Step("goto", place="shipping"), Step("dock"),
    ]  # fmt: skip
    assert steps_from_words("undock", places) == [Step("undock")]
    with pytest.raises(WatchError, match="not 'read the battery'"):
        steps_from_words("read the battery", places)
    with pytest.raises(WatchError, match="no place named in 'go to atlantis'"):
        steps_from_words("go to atlantis", places)


class _NoConveyor:
    def has(self, role):
        return role != "conveyor"


def test_a_robot_without_a_conveyor_keeps_no_conveyor_watch():
    with pytest.raises(WatchError, match="this robot reports no conveyor"):
        validate(Watch("conveyor", ">=", 1.0), _NoConveyor())


def test_the_new_kinds_fire_from_the_evaluator_and_round_trip_the_store(store):
    from astiop.transports.state import Conveyor, Pose2D

    pid = _add(store, Watch("place", "<=", 0.3, place="shipping", x=37.6, y=4.0))
    cid = _add(store, Watch("conveyor", ">=", 1.0))
    assert store.watch(pid)["place"] == "shipping" and Watch.from_row(store.watch(pid)).x == 37.6
    ev = Evaluator(store, builtins=False)
    far = RobotState(0, pose=Pose2D(30.0, 4.0, 0.0), conveyor=Conveyor(False, 0, False, "off"))
    assert ev.step(far, now=0) == []
    near = RobotState(1, pose=Pose2D(37.5, 4.1, 0.0), conveyor=Conveyor(False, 0, True, "on"))
    fired = ev.step(near, now=1)
    assert sorted(a["watch_id"] for a in fired) == [pid, cid]


def test_a_no_progress_watch_fires_once_the_goal_has_stalled_that_long(store):
    from astiop.transports.state import Pose2D

    _add(store, Watch("no_progress", ">=", 10.0))
    ev = Evaluator(store, builtins=False)
    going = Status("navigating", "auto", "shipping", "", 0.0, False, False)

    def at(t):
        return RobotState(t, pose=Pose2D(5.0, 5.0, 0.0), status=going)

    assert ev.step(at(0), now=0) == [] and ev.step(at(9), now=9) == []
    assert [a["kind"] for a in ev.step(at(10.5), now=10.5)] == ["watch"]


def test_a_watch_answered_to_a_request_that_is_none_is_scored_something_else():
    """The scorer can fail: "tell me the battery level" answered with a watch is not right,
    and not an honest decline either."""
    from astiop.agent.result import TurnResult
    from astiop.bench import questions
    from astiop.bench.library import builtin

    case = next(c for c in builtin("watches").cases if c.id == "not02")
    said = (
        "Not watched: watches are kept in astiop's database, and there is none here; it would "
        "be: I will tell you when the battery is below 85.0 % (once)."
    )
    assert (
        questions.verdict(case, TurnResult("rules", "rules", case.request, answer=said)) == "other"
    )


def test_words_that_name_neither_a_robot_nor_a_place_are_no_place_watch():
    """ "when battery reaches 20" is not read as a robot called 'battery' going to a place '20':
    it is the battery's watch; a robot word or a known robot still gets its line."""
    from astiop.watches.model import WatchError
    from astiop.watches.words import watch_from_words

    places = {"shipping": (37.6, 4.0)}
    reached = watch_from_words("tell me when battery reaches 20", "", places, battery_now=85.0)
    assert reached is not None and reached.condition() == "the battery is at most 20 %"
    assert watch_from_words("tell me when the pallet reaches 20", "", places) is None
    with pytest.raises(WatchError, match="no place called 'packing'"):
        watch_from_words("tell me when it arrives at packing", "", places)
    with pytest.raises(WatchError, match="no robot named 'someone'"):
        watch_from_words("tell me when someone arrives at shipping", "", places)


def test_the_battery_reaching_a_level_goes_the_way_said_or_from_where_it_is_now():
    def sentence(said: str, now: float | None = None) -> str:
        found = watch_from_words(said, battery_now=now)
        assert found is not None, said
        return found.condition()

    assert sentence("tell me when the battery reaches 20 %", 85.0) == "the battery is at most 20 %"
    assert sentence("tell me when the battery reaches 90 %", 85.0) == "the battery is at least 90 %"
    assert sentence("let me know when the battery drops to 30%") == "the battery is at most 30 %"
    assert sentence("tell me when the battery is charged to 95 %") == "the battery is at least 95 %"
    assert sentence("tell me when battery hits 50", 85.0) == "the battery is at most 50 %"
    with pytest.raises(WatchError, match="no reading of it here\\): say 'below 20 %' or"):
        watch_from_words("tell me when the battery reaches 20 %")
    with pytest.raises(WatchError, match="it is at 85.0 % now"):
        watch_from_words("tell me when the battery gets to 85 %", battery_now=85.0)


def test_an_alert_s_reading_is_shown_with_its_age_and_a_dash_for_none():
    from astiop.watches.alert_text import reading_text

    assert reading_text({"reading": "85.00 %", "reading_age_s": 0.123}) == "85.00 % (0.12 s old)"
    assert reading_text({"reading": None, "reading_age_s": 0.5}) == "- (0.50 s old)"  # not "None"
    assert reading_text({"reading": "", "reading_age_s": None}) == "-"
