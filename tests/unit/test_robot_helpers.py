"""The gateway's helpers built alone, with no gateway: the E-STOP latch (robot/estop_latch.py),
handed a robot's backend and a store, and the reading of the robot's graph
(robot/graph_reading.py), handed a backend, a safety policy and a store."""

from __future__ import annotations

import sqlite3
import threading
import time
from collections.abc import Callable
from typing import Any

from astiop.robot import graph_reading
from astiop.robot.estop_latch import HELD_FOR_ALL, EstopLatch
from astiop.robot.graph_reading import GraphReading
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.grammar import parse
from astiop.ros2.validation import Checked, validate
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from tests.ros import until

BACK_UP = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.2}}'"
STOP = 'ros2 service call /stop std_srvs/srv/Trigger "{}"'


SAID: dict[int, list[str]] = {}  # what each latch said of its store, by id


def latch_on(store: Store, who: str = "console", latch_key: str = "") -> EstopLatch:
    said: list[str] = []
    latch = EstopLatch(
        SimBackend(Simulator(seed=0), store),
        store,
        who=who,
        latch_key=latch_key,
        say_store_error=said.append,
    )
    SAID[id(latch)] = said
    return latch


def actuation(text: str) -> Checked:
    """A motion command by its names alone (no robot's graph to check it against)."""
    return Checked(text, parse(text), True, kind="actuate")


# -- the E-STOP latch ----------------------------------------------------------------------
def test_a_press_stops_the_robot_and_holds_every_process_on_the_database(tmp_path):
    db = tmp_path / "shared.db"
    mine, theirs = latch_on(Store(db), "console"), latch_on(Store(db), "mcp")
    assert not mine.latched and not theirs.latched
    assert mine.estop() == []
    assert mine.backend.e_stopped and mine.e_stopped
    assert mine.store is not None and mine.store.estop_latch()["by"] == "console"
    assert theirs.latched and not theirs.backend.e_stopped, "not followed until it looks"
    assert theirs.follow_latch() and theirs.backend.e_stopped
    catalog = theirs.backend.catalog
    assert theirs.held_by_estop(validate(BACK_UP, catalog))
    assert not theirs.held_by_estop(validate(STOP, catalog)), "/stop always goes through"
    assert mine.release_estop() == [] and not mine.backend.e_stopped
    assert not theirs.follow_latch() and not theirs.backend.e_stopped
    assert not theirs.held_by_estop(validate(BACK_UP, catalog))
    assert SAID[id(mine)] == [] and SAID[id(theirs)] == []


def test_a_press_with_no_database_nor_graph_holds_until_this_process_releases_it():
    """A gateway with no store (the bench, the E-STOP button's): looking at the latch, as every
    state read does, never lets the robot go (it did: no store read as 'released')."""
    latch = EstopLatch(SimBackend(Simulator(seed=0), None), None, who="t", say_store_error=print)
    assert latch.estop() == [] and latch.e_stopped
    assert latch.follow_latch() and latch.e_stopped and latch.backend.e_stopped
    assert latch.held_by_estop(validate(BACK_UP, latch.backend.catalog))
    assert latch.release_estop() == [] and not latch.follow_latch() and not latch.e_stopped


def test_a_restart_keeps_the_estop_until_it_is_released(tmp_path):
    store = Store(tmp_path / "a.db")
    store.latch_estop("yesterday's console")
    kept = latch_on(store)
    assert kept.latched and not kept.backend.e_stopped
    kept.restore()
    assert kept.backend.e_stopped
    kept.release_estop()
    fresh = latch_on(store)
    fresh.restore()
    assert not fresh.backend.e_stopped


def test_a_fleet_robot_latches_its_own_estop_and_a_whole_domain_process_holds_it(tmp_path):
    db = tmp_path / "fleet.db"
    tb3_1, whole = latch_on(Store(db), latch_key="/tb3_1"), latch_on(Store(db))
    assert tb3_1.estop() == []
    assert whole.store is not None
    assert whole.store.latched_robots() == ["/tb3_1"] and whole.store.estop_latch() is None
    assert not whole.latched, "its own robot is not that one"
    to_it = "ros2 topic pub --once /tb3_1/cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.2}}'"
    assert whole.held_by_estop(actuation(to_it))
    assert not whole.held_by_estop(actuation(to_it.replace("tb3_1", "tb3_2")))
    assert whole.estop() == []  # every robot's
    assert tb3_1.release_estop() == [HELD_FOR_ALL]
    assert tb3_1.backend.e_stopped, "a robot under every robot's E-STOP stays stopped"
    assert whole.release_estop() == [] and tb3_1.release_estop() == []
    assert not whole.latched and not tb3_1.latched and not tb3_1.backend.e_stopped


def test_what_moves_a_fleet_robot_ends_when_its_own_estop_latches_elsewhere(tmp_path):
    db = tmp_path / "fleet.db"
    whole, tb3_1 = latch_on(Store(db)), latch_on(Store(db), latch_key="/tb3_1")
    inflight = whole.backend.inflight
    with (
        inflight.running("teleop /tb3_2", "/tb3_2/cmd_vel") as other,
        inflight.running("teleop /tb3_1", "/tb3_1/cmd_vel") as job,
    ):
        tb3_1.estop()
        assert not whole.follow_latch(), "the whole domain is not latched"
        assert job.ended_by_estop and not other.ended_by_estop


def test_a_store_that_cannot_be_read_or_written_never_undoes_a_press(tmp_path, monkeypatch):
    store = Store(tmp_path / "a.db")
    latch = latch_on(store)

    def broken(*_args: Any) -> None:
        raise sqlite3.OperationalError("disk I/O error")

    monkeypatch.setattr(store, "latch_estop", broken)
    failures = latch.estop()
    assert latch.backend.e_stopped, "the robot is stopped first, whatever the store does"
    assert failures == ["the E-STOP is not latched in the database: disk I/O error"]
    monkeypatch.setattr(store, "estop_latch", broken)
    assert latch.latched, "unreadable: what this process saw last holds"
    assert SAID[id(latch)] == ["the E-STOP latch could not be read: disk I/O error"]
    assert not latch_on(store).latched, "a process that never saw a press holds none"


class Graph:
    """A robot's graph in memory: every station's channel hears every word said on it, and a
    channel opened later hears each station's last word at once (transient-local). `lost`: how
    many words carrying a release are lost on the way to every other station (a loaded
    machine)."""

    def __init__(self, lost: int = 0) -> None:
        self.last: dict[int, dict[str, Any]] = {}
        self.heard: dict[int, Callable[[dict[str, Any]], None]] = {}
        self.lock = threading.Lock()
        self.lost = lost

    def channel(self, _namespace: str, on_word: Callable[[dict[str, Any]], None]) -> Channel:
        channel = Channel(self, on_word)
        with self.lock:
            self.heard[id(channel)] = on_word
            words = list(self.last.values())
        for word in words:
            on_word(word)
        return channel


class Channel:
    def __init__(self, graph: Graph, on_word: Callable[[dict[str, Any]], None]):
        self.graph = graph
        self.on_word = on_word
        self.said: dict[str, Any] | None = None

    def announce(self, word: dict[str, Any], _timeout_s: float | None = None) -> None:
        with self.graph.lock:
            self.said = word
            if word.get("release") is not None and self.graph.lost > 0:
                self.graph.lost -= 1
                return
            self.graph.last[id(self)] = word
            heard = list(self.graph.heard.values())
        for on_word in heard:
            on_word(word)

    def settle(self, _timeout_s: float, _least_s: float) -> bool:
        return True

    def words(self) -> list[dict[str, Any]]:
        with self.graph.lock:
            return list(self.graph.last.values())

    def close(self) -> None:  # its writer, and its word, go with it
        with self.graph.lock:
            self.graph.heard.pop(id(self), None)
            self.graph.last.pop(id(self), None)


def stations_on(graph: Graph, tmp_path, monkeypatch, *names: str) -> list[EstopLatch]:
    """A station per name, each with its own database, on `graph`, its first words heard."""
    latches = [latch_on(Store(tmp_path / f"{name}.db")) for name in names]
    for latch in latches:
        monkeypatch.setattr(latch.backend, "estop_channel", graph.channel)
        latch.follow_stations("")
        assert latch.station_latch is not None and latch.station_latch.wait_ready(5)
    return latches


def test_stations_on_one_graph_hold_each_other_whatever_their_databases(tmp_path, monkeypatch):
    here, there = stations_on(Graph(), tmp_path, monkeypatch, "here", "there")
    try:
        here.estop()
        assert until(lambda: there.backend.e_stopped, 5), "a press at one station holds all"
        pressed = there.pressed_by()
        assert pressed is not None and pressed.who == "console"
        assert there.store is not None and there.store.estop_latch() is None, (
            "a press heard on the graph is not written in another database"
        )
        here.release_estop()
        assert until(lambda: not there.backend.e_stopped, 5), "and its release frees all"
        assert not there.latched and there.pressed_by() is None
    finally:
        here.close()
        there.close()


def test_a_release_said_as_its_station_ends_is_said_until_every_other_station_has_it(
    tmp_path, monkeypatch
):
    """A one-shot `astiop estop --release` ends right after its release, and its word goes with
    its writer: a word lost on the way (a loaded machine) must not leave a keeper holding."""
    graph = Graph()
    keeper, releaser = stations_on(graph, tmp_path, monkeypatch, "keeper", "releaser")
    try:
        keeper.estop()
        assert until(lambda: releaser.pressed_by() is not None, 5)
        graph.lost = 2  # the release's first words never arrive
        releaser.release_estop()
        releaser.close()
        assert keeper.station_latch is not None and not keeper.station_latch.engaged, (
            "the releasing station ended before the keeper heard its release"
        )
    finally:
        keeper.close()


# -- the reading of the robot's graph ------------------------------------------------------
def test_the_robots_map_fences_its_goals_and_names_the_stores_places(tmp_path):
    store = Store(tmp_path / "a.db")
    backend = SimBackend(Simulator(seed=0), store)
    safety = SafetyPolicy(geofence=None)
    reading = GraphReading(backend, safety, store, 5.0)
    assert reading.catalog is backend.catalog and "/cmd_vel" in reading.catalog.topics
    assert reading.profile.name("velocity_command") == "/cmd_vel"
    reading.use_map()
    fence = reading.profile.map.geofence or backend.map_geometry().bounds
    assert fence is not None and safety.geofence == fence
    assert store.map_name == reading.profile.map_name


def test_a_service_is_found_at_once_and_one_missing_is_said_once_the_graph_settles(
    tmp_path, monkeypatch
):
    monkeypatch.setattr(graph_reading, "SETTLED_S", 0.3)
    backend = SimBackend(Simulator(seed=0))
    reading = GraphReading(backend, SafetyPolicy(), None, 5.0)
    assert reading.serves("/goto_position", 5.0)
    t0 = time.monotonic()
    assert not reading.serves("/dock_elsewhere", 5.0)
    assert 0.3 <= time.monotonic() - t0 < 3.0, "settled, not timed out"
    assert reading.confirm_missing() == reading.profile  # a robot not discovering: as it is


class Discovering(SimBackend):
    """A robot discovered in rounds: its /battery_status heard at the third read of its graph."""

    def __init__(self) -> None:
        super().__init__(Simulator(seed=0))
        self.battery = self.catalog.topics.pop("/battery_status")
        self.reads = 0

    def discovering(self) -> bool:
        return self.reads < 5

    def refresh(self, settle: bool = True) -> bool:
        self.reads += 1
        if self.reads == 3:
            self.catalog.topics["/battery_status"] = self.battery
        return True


def test_a_name_missing_from_half_a_graph_is_looked_for_until_it_is_heard():
    backend = Discovering()
    reading = GraphReading(backend, SafetyPolicy(), None, 5.0)
    text = "ros2 topic echo /battery_status --once"
    missing = validate(text, reading.catalog)
    assert not missing.valid and missing.reason.startswith("there is no")
    found = reading.checked_once_heard(text, missing)
    assert found.valid and backend.reads == 3
