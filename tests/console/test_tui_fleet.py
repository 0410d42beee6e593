"""The Fleet screen (F7) through Pilot, on three simulated ASTIbots in one warehouse: every robot
listed live, the current one marked and named, filtered and sorted, and ctrl+e stopping all of
them (ctrl+r releasing all, after a question that names them)."""

from __future__ import annotations

import re
import time

from textual.widgets import DataTable, Input, Select, Static

from astiop.app import make_app
from astiop.config import load_settings
from astiop.robot.factory import make_safety
from astiop.robot.fleet import robot_settings
from astiop.robot.fleet_watch import FleetWatch
from astiop.robot.gateway import RobotGateway
from astiop.robot.lease import Lease, lease_key
from astiop.screens.modals import ConfirmModal
from astiop.sim.fleet import SimFleet
from astiop.sim.runner import SimRunner
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from tests.tui_helpers import wait_for

NAMES = ["astibot_1", "astibot_2", "astibot_3"]


def _gateway(settings, sim, store=None, name: str = "") -> RobotGateway:
    backend = SimBackend(sim, store, stepped_elsewhere=True)
    gateway = RobotGateway(backend, make_safety(settings, store), store=store, who="test",
                           latch_key=f"/{name}" if name else "")  # fmt: skip
    if name:  # shared, as a robot on a ROS 2 graph is: one console controls it
        gateway.lease = Lease(store, lease_key(f"/{name}", 0), name, "console")
    return gateway


def fleet_console(tmp_path):
    settings = load_settings(
        {
            "llm": {"model": "rules"},
            "robot": {"namespace": "/astibot_2"},
            "fleet": {"discover": "auto"},
        },
        env={},
        path=tmp_path / "none.toml",
    )
    fleet = SimFleet(NAMES)
    store = Store(tmp_path / "console.db")
    watch = FleetWatch(
        [(n, f"/{n}", lambda sim=sim, n=n: _gateway(settings, sim, store, n)) for n, sim in
         zip(NAMES, fleet.robots, strict=True)],
        period_s=0.1,
    )  # fmt: skip
    watch.settings_for = lambda name: robot_settings(settings, name)
    gateway = _gateway(settings, fleet.robots[1], store, "astibot_2")
    app = make_app(settings, store, gateway=gateway, sample_hz=10.0, fleet=watch)
    return app, fleet, SimRunner(fleet, speed=5.0)


async def test_a_robot_found_after_the_console_opened_is_listed_and_stopped_with_the_rest(
    tmp_path,
):
    app, fleet, runner = fleet_console(tmp_path)
    watch = app.fleet
    late = watch.robots.pop()  # astibot_3 joins the graph after the console opened
    del watch._rows[late[0]]
    polls = iter([[], [], [late]])  # found at the third look at the graph
    watch.find_more = lambda: next(polls, [])
    runner.start()
    try:
        async with app.run_test(size=(150, 40)) as pilot:
            await pilot.press("f7")
            await wait_for(pilot, lambda: len(_rows(app)) == 3 and "%" in _rows(app)[2][2])
            assert [r[0].strip("▶ ") for r in _rows(app)] == NAMES
            assert "3 robots:" in app.screen.sub_title
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: all(r.e_stopped for r in fleet.robots))
    finally:
        runner.stop()


def _rows(app) -> list[list[str]]:
    table = app.screen.query_one(DataTable)
    return [[str(c) for c in table.get_row_at(i)] for i in range(table.row_count)]


async def test_every_robot_is_listed_filtered_sorted_and_stopped_at_once(tmp_path):
    app, fleet, runner = fleet_console(tmp_path)
    runner.start()
    try:
        async with app.run_test(size=(150, 40)) as pilot:
            assert "astibot_2" in app.sub_title  # the current robot, on every screen
            await pilot.press("f7")
            await wait_for(pilot, lambda: len(_rows(app)) == 3 and "%" in _rows(app)[2][2])
            await wait_for(pilot, lambda: _rows(app)[1][7] == "this console")
            rows = _rows(app)
            assert [r[0].strip("▶ ") for r in rows] == NAMES
            assert rows[1][0].startswith("▶") and rows[0][7] == "free"
            assert all(r[1] == "charging" for r in rows) and "3 robots: 3 charging" in (
                app.screen.sub_title
            )
            current = str(app.screen.query_one("#fleet-current", Static).render())
            assert "current robot: astibot_2" in current

            fleet.robots[2].battery.soc = 0.12  # low: the filter keeps it alone
            await pilot.press("f")
            await wait_for(pilot, lambda: [r[0].strip() for r in _rows(app)] == ["astibot_3"])
            assert "(1 low battery)" in app.screen.sub_title
            await pilot.press("f", "f", "s")  # back to all, then sorted by battery
            await wait_for(pilot, lambda: _rows(app)[0][0].strip() == "astibot_3")
            assert "sorted by battery" in app.screen.sub_title

            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: all(r.e_stopped for r in fleet.robots))
            await wait_for(pilot, lambda: all(r[1] == "e_stopped" for r in _rows(app)))
            store = app.services.store  # each robot latched on its own
            assert store.latched_robots() == [f"/{n}" for n in NAMES]
            assert store.estop_latch() is None

            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert "astibot_1, astibot_2, astibot_3" in app.screen.question
            await pilot.press("y")
            await wait_for(pilot, lambda: not any(r.held for r in fleet.robots))
            await wait_for(pilot, lambda: all(r[1] == "charging" for r in _rows(app)))
    finally:
        runner.stop()


async def test_enter_makes_a_robot_current_and_chat_moves_the_robot_a_request_names(tmp_path):
    app, fleet, runner = fleet_console(tmp_path)
    other = Lease(Store(tmp_path / "console.db"), lease_key("/astibot_1", 0), "astibot_1",
                  "astiop mcp")  # fmt: skip
    assert other.take() is None  # another process controls astibot_1
    runner.start()
    try:
        async with app.run_test(size=(150, 40)) as pilot:
            await pilot.press("f7")
            await wait_for(pilot, lambda: "astiop mcp" in _rows(app)[0][7])
            await pilot.press("down", "down", "enter")  # astibot_3
            await wait_for(pilot, lambda: app.current_robot == "astibot_3")
            assert "astibot_3" in app.sub_title and app.services.settings.robot.namespace == (
                "/astibot_3"
            )
            await wait_for(pilot, lambda: _rows(app)[2][7] == "this console")

            await pilot.press("f2")
            chat = app.screen
            for robot, soc in zip(fleet.robots, (0.55, 0.7, 0.9), strict=True):
                robot.battery.soc = soc
            await wait_for(pilot, lambda: app.fleet.rows()[0].battery < 0.6)
            await _ask(pilot, chat, "which robot has the lowest battery?")
            said = await _answer(pilot, chat, "has the lowest battery")
            m = re.match(r"astibot_1 has the lowest battery: (\d+\.\d) %\.", said)
            assert m and 55 <= float(m[1]) <= fleet.robots[0].battery.soc * 100 + 0.05, said

            await _ask(pilot, chat, "send astibot 2 to shipping")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert "Run this command on astibot_2?" in app.screen.question
            await pilot.press("y")
            await wait_for(pilot, lambda: fleet.robots[1].goal is not None)
            assert fleet.robots[0].goal is None and fleet.robots[2].goal is None
            said = await _answer(pilot, chat, "astibot_2: ")
            assert "shipping" in said, said

            # one robot stopped from the Fleet screen: the others still move
            await pilot.press("f7")
            await wait_for(pilot, lambda: _rows(app)[2][0].startswith("▶"))
            await pilot.press("x")  # the cursor is on astibot_3
            await wait_for(pilot, lambda: fleet.robots[2].e_stopped)
            assert app.services.store.latched_robots() == ["/astibot_3"]
            assert not fleet.robots[0].e_stopped and not fleet.robots[1].e_stopped
            await pilot.press("r")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert app.screen.question.startswith("Release the E-STOP of astibot_3?")
            await pilot.press("y")
            await wait_for(pilot, lambda: not fleet.robots[2].e_stopped)
            assert app.services.store.latched_robots() == []
            await pilot.press("f2")

            # astibot_1 is another's: its motion is refused, saying who controls it
            await _ask(pilot, chat, "send astibot 1 to shipping")
            await wait_for(pilot, lambda: "controlled by astiop mcp" in " ".join(_said(chat)))
            assert fleet.robots[0].goal is None

            # Logs: each turn and event with its robot, filtered by robot
            await pilot.press("f3")
            logs = app.screen
            await wait_for(pilot, lambda: len(logs.query_one("#logs-robot", Select)._options) > 2)
            logs.query_one("#logs-robot", Select).value = "astibot_2"
            await wait_for(pilot, lambda: logs.shown and all(r["robot"] == "astibot_2"
                                                             for r in logs.shown))  # fmt: skip
            assert any(r["summary"] == "send the robot to shipping" for r in logs.shown)
    finally:
        runner.stop()
        other.release()
        other.store.close()


async def _ask(pilot, chat, text: str) -> None:
    chat.query_one(Input).value = text
    await pilot.press("enter")


async def _answer(pilot, chat, part: str) -> str:
    def found() -> str | None:
        return next((str(w.render()) for w in chat.query(".answer") if part in str(w.render())),
                    None)  # fmt: skip

    await wait_for(pilot, found, what=f"an answer with {part!r}")
    return found()


def _said(chat) -> list[str]:
    return [str(w.render()) for w in chat.query("Static")]


def test_a_robot_not_reached_is_its_own_red_row_and_its_stop_a_failure(tmp_path):
    settings = load_settings({}, env={}, path=tmp_path / "none.toml")
    fleet = SimFleet(["near"])

    def unreachable():
        raise ConnectionError("no route to /far")

    watch = FleetWatch(
        [
            ("near", "/near", lambda: _gateway(settings, fleet.robots[0])),
            ("far", "/far", unreachable),
        ],
        period_s=0.05,
    ).start()
    try:
        rows = {}
        for _ in range(100):
            rows = {r.name: r for r in watch.rows()}
            if rows["far"].error and rows["near"].battery is not None:
                break
            time.sleep(0.05)
        assert rows["far"].error == "not reached: no route to /far"
        assert rows["near"].state == "idle" and not rows["near"].error
        failures = watch.estop_all()
        # the robot's own /stop is called on the transport's thread: it holds a moment later
        deadline = time.monotonic() + 10
        while not fleet.robots[0].e_stopped and time.monotonic() < deadline:
            time.sleep(0.05)
        assert failures["near"] == [] and fleet.robots[0].e_stopped
        assert failures["far"] == ["not reached: no connection to it"]
    finally:
        watch.close()


async def test_ctrl_t_lets_go_of_control_after_a_question_and_takes_it_back(tmp_path):
    app, _fleet, _runner = fleet_console(tmp_path)
    other = Lease(Store(tmp_path / "console.db"), lease_key("/astibot_2", 0), "astibot_2",
                  "another console")  # fmt: skip
    try:
        async with app.run_test(size=(150, 40)) as pilot:
            await wait_for(pilot, lambda: "in control" in app.sub_title)
            assert other.take() is not None  # held by this console
            await pilot.press("ctrl+t")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert app.screen.question.startswith("Let go of control of astibot_2?")
            await pilot.press("y")
            await wait_for(pilot, lambda: "WATCHING" in app.sub_title)
            assert other.take() is None  # free: taken without taking it over
            await pilot.press("ctrl+t")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert "Take control of astibot_2 from another console" in app.screen.question
            await pilot.press("y")
            await wait_for(pilot, lambda: "in control" in app.sub_title)
            await wait_for(pilot, lambda: not other.held)  # told it was taken over
    finally:
        other.release()
        other.store.close()
