"""The Fleet screen (F7) through Pilot, on three simulated ASTIbots in one warehouse: every robot
listed live, the current one marked and named, filtered and sorted, and ctrl+e stopping all of
them (ctrl+r releasing all, after a question that names them)."""

from __future__ import annotations

import time

from textual.widgets import DataTable, Static

from astiop.app import make_app
from astiop.config import load_settings
from astiop.robot.backends.sim.backend import SimBackend
from astiop.robot.factory import make_safety
from astiop.robot.fleet_watch import FleetWatch
from astiop.robot.gateway import RobotGateway
from astiop.screens.modals import ConfirmModal
from astiop.sim.fleet import SimFleet
from astiop.sim.runner import SimRunner
from astiop.store import Store
from tests.tui_helpers import wait_for

NAMES = ["astibot_1", "astibot_2", "astibot_3"]


def _gateway(settings, sim, store=None) -> RobotGateway:
    backend = SimBackend(sim, store, stepped_elsewhere=True)
    return RobotGateway(backend, make_safety(settings, store), store=store, who="test")


def fleet_console(tmp_path):
    settings = load_settings(
        {"llm": {"model": "rules"}, "robot": {"namespace": "/astibot_2"}},
        env={},
        path=tmp_path / "none.toml",
    )
    fleet = SimFleet(NAMES)
    store = Store(tmp_path / "console.db")
    watch = FleetWatch(
        [(n, f"/{n}", lambda sim=sim: _gateway(settings, sim)) for n, sim in
         zip(NAMES, fleet.robots, strict=True)],
        period_s=0.1,
    )  # fmt: skip
    gateway = _gateway(settings, fleet.robots[1], store)
    app = make_app(settings, store, gateway=gateway, sample_hz=10.0, fleet=watch)
    return app, fleet, SimRunner(fleet, speed=5.0)


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
            rows = _rows(app)
            assert [r[0].strip("▶ ") for r in rows] == NAMES
            assert rows[1][0].startswith("▶") and rows[1][7] == "this console"
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
            assert app.services.store.estop_latch() is not None

            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert "astibot_1, astibot_2, astibot_3" in app.screen.question
            await pilot.press("y")
            await wait_for(pilot, lambda: not any(r.held for r in fleet.robots))
            await wait_for(pilot, lambda: all(r[1] == "charging" for r in _rows(app)))
    finally:
        runner.stop()


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
        assert failures["near"] == [] and fleet.robots[0].e_stopped
        assert failures["far"] == ["not reached: no connection to it"]
    finally:
        watch.close()
