"""The console on the real-robot path (an emulated robot in its own process), and what must never
end the app: markup in stored text, a collision fault, an E-STOP during a confirmation."""

from __future__ import annotations

import pytest
from rich.text import Text
from textual.widgets import DataTable, Input

from astiop.app import make_app
from astiop.config import load_settings
from astiop.sim.simulator import Simulator
from astiop.store import Store
from tests.emulator import ARMED_ESTOP, emulated_robot, on_path, ros2_calls
from tests.tui_helpers import console, sim_of, wait_for

SIZE = (120, 40)


def ros2_console(tmp_path):
    cfg = load_settings(
        {"llm": {"model": "rules"}, "robot": {"backend": "ros2", "ros2_transport": "cli"}},
        env={},
        path=tmp_path / "none.toml",
    )
    return make_app(cfg, Store(tmp_path / "console.db"))


@pytest.mark.slow
async def test_ros2_dashboard_and_estop_during_a_confirmation(tmp_path, monkeypatch):
    with emulated_robot() as robot:
        on_path(monkeypatch, robot)
        app = ros2_console(tmp_path)
        async with app.run_test(size=SIZE) as pilot:

            def shown(widget_id: str) -> str:
                return str(app.screen.query_one(widget_id).render())

            # what the operator sees, once the screen has taken the robot's first messages
            await wait_for(pilot, lambda: "85." in shown("#battery"))
            await wait_for(pilot, lambda: "CHARGING" in shown("#robot"))
            # each topic comes on its own stream: the pose may follow the status
            await wait_for(pilot, lambda: "x   1.15 m" in shown("#robot"))
            await pilot.press("f2")
            await pilot.pause()
            app.screen.query_one(Input).value = "send the robot to shipping"
            await pilot.press("enter")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "ConfirmModal")
            await pilot.press("ctrl+e")  # E-STOP while the operator is being asked
            await pilot.pause()
            await pilot.press("y")  # too late: the E-STOP answered "no"
            await app.workers.wait_for_complete()
            assert app.services.gateway.e_stopped
        calls = ros2_calls(robot)
        assert not any(c[:3] == ["service", "call", "/goto_position"] for c in calls)
        assert ARMED_ESTOP in calls


@pytest.mark.slow
async def test_ros2_teleop_moves_the_robot(tmp_path, monkeypatch):
    with emulated_robot(speed=4.0) as robot:
        on_path(monkeypatch, robot)
        app = ros2_console(tmp_path)
        async with app.run_test(size=SIZE) as pilot:
            gateway = app.services.gateway
            gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=lambda _c: True)

            def idle() -> bool:
                st = app.robot_state
                return st.pose is not None and st.status is not None and st.status.state == "idle"

            await wait_for(pilot, idle)
            x0 = app.robot_state.pose.x
            await pilot.press("f5")
            for _ in range(6):  # each key press is waited on until the app is idle
                await pilot.press("s")  # it faces west: backwards is +x
                await pilot.pause(0.1)
            await wait_for(pilot, lambda: app.robot_state.pose.x > x0 + 0.2)
            assert type(app.screen).__name__ == "TeleopScreen"


async def test_markup_in_stored_text_renders_as_text(tmp_path):
    app = console(tmp_path)
    store = app.services.store
    store.add_location("bay_1", 5.0, 5.0, 0.0, "[/] [bold]not bold[/bold] [/scan]")
    iid = store.start_interaction(model="rules", mode="rules", prompt="what does [/scan] show")
    store.update_interaction(iid, status="done", answer="[/]")
    async with app.run_test(size=SIZE) as pilot:
        for _ in range(2):  # and again on a later visit
            await pilot.press("f3")
            await app.workers.wait_for_complete()
            await pilot.pause()
            table = app.screen.query_one(DataTable)
            cells = [table.get_row_at(i)[-1] for i in range(table.row_count)]
            assert Text("what does [/scan] show") in cells
            await pilot.press("f4")
            await pilot.pause()
            table = app.screen.query_one(DataTable)
            rows = [table.get_row_at(i) for i in range(table.row_count)]
            bay = next(r for r in rows if r[0].plain == "bay_1")
            assert bay[-1].plain == "[/] [bold]not bold[/bold] [/scan]"


async def test_teleop_into_a_shelf_faults_but_the_app_runs_on(tmp_path):
    sim = Simulator(seed=0, start=(11.0, 5.0, 1.5708))  # facing a shelf row to the north
    app = console(tmp_path, sim=sim)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f5")
        await pilot.press("plus", "plus")
        for _ in range(60):
            await pilot.press("w")
            await app.workers.wait_for_complete()
            sim_of(app).step(0.1)
            if sim_of(app).fault:
                break
        assert sim_of(app).fault.startswith("collision")
        await pilot.press("w")  # a faulted base refuses: a notification, not a crash
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert app.is_running and type(app.screen).__name__ == "TeleopScreen"
