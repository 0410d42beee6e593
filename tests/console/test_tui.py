"""The console driven with Pilot: what an operator does on each screen."""

import math
import re
import threading

import numpy as np
from textual.app import App
from textual.widgets import DataTable, Input

from astiop.screens.registry import SCREENS
from astiop.sim.simulator import Simulator
from astiop.transports.state import OccupancyGrid, Pose2D, RobotState
from astiop.widgets.map_view import Place, WarehouseMapView
from tests.tui_helpers import ask, console, sim_of, wait_for

SIZE = (120, 40)


async def test_function_keys_switch_screens(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        assert [s.key for s in SCREENS] == [f"f{i}" for i in range(1, len(SCREENS) + 1)]
        for entry in [*SCREENS[1:], SCREENS[0]]:  # the Dashboard shows first: it comes last
            await pilot.press(entry.key)
            await pilot.pause()
            assert type(app.screen) is entry.screen, entry.key


async def test_the_robot_line_keeps_its_words_apart(tmp_path):
    sim = Simulator(seed=0)
    sim.step(1.0)  # on the dock: charging
    app = console(tmp_path, sim=sim)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        line = str(app.screen.query_one("#robot").render()).splitlines()[0]
        assert line.startswith("robot  CHARGING   mode auto   t 1.0 s")
        # SVG viewers such as librsvg drop the spaces a text run starts with: in the snapshot
        # each gap must end the run before it, or the line reads "CHARGINGmode auto"
        svg = app.export_screenshot()
        assert "CHARGING&#160;&#160;&#160;</text>" in svg
        assert not re.search(r">(&#160;)+mode&#160;auto", svg)


async def test_the_dashboard_follows_a_still_robots_clock(tmp_path):
    # a still robot is redrawn less often than it is sampled, but what changes still shows
    sim = Simulator(seed=0)
    sim.step(1.0)  # on the dock: charging, still
    app = console(tmp_path, sim=sim)
    async with app.run_test(size=SIZE) as pilot:
        panel = app.screen.query_one("#robot")
        await wait_for(pilot, lambda: "t 1.0 s" in str(panel.render()))
        sim.step(0.5)
        await wait_for(pilot, lambda: "t 1.5 s" in str(panel.render()))


def map_text(view) -> str:
    return "\n".join(view.render_line(y).text for y in range(view.size.height))


async def test_the_map_names_the_stations_and_says_what_its_colours_are(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        text = map_text(app.screen.query_one(WarehouseMapView))
        for name in ("charging_dock", "assembly_station", "cps_storage", "shipping"):
            assert name in text
        assert "inspection_zone_a" in text and "inspection_zone_b" in text
        for what in ("robot", "heading", "path", "LiDAR hits", "obstacles seen", "walls"):
            assert what in text
        for what in ("racks", "stations", "zones", "locations"):
            assert what in text


class MapOnly(App):
    def __init__(self, geometry, state: RobotState):
        super().__init__()
        self.geometry, self.state = geometry, state

    def compose(self):
        yield WarehouseMapView(self.geometry)

    def on_mount(self) -> None:
        view = self.query_one(WarehouseMapView)
        view.set_locations([Place("bay_9", 12.5, 3.0), Place("far_away", 90.0, 12.0)])
        view.show(self.state)


async def test_the_map_names_stored_locations_on_a_robots_grid_and_with_no_map():
    cells = np.zeros((250, 400), dtype=np.int8)  # 40 x 25 m at 0.1 m, walls all round
    cells[:3, :] = cells[-3:, :] = cells[:, :3] = cells[:, -3:] = 100
    grid = OccupancyGrid(0.1, 0.0, 0.0, 400, 250, cells)
    robot = RobotState(t=0.0, pose=Pose2D(20.0, 12.0, 0.0))
    for geometry, legend in ((grid, "occupied (/map)"), (None, "the view follows the robot")):
        app = MapOnly(geometry, robot)
        async with app.run_test(size=(72, 30)) as pilot:
            await pilot.pause()
            text = map_text(app.query_one(WarehouseMapView))
            assert "bay_9" in text and legend in text and "locations" in text
            assert "far_away" not in text  # off the view: not written at an edge
            assert "racks" not in text  # nothing a grid cannot show


async def test_chat_answers_and_logs_it(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        text = await ask(app, pilot, "what is the battery level?")
        assert "battery 85.0 %" in text
        assert app.services.store.interactions()[0]["status"] == "done"
        rows = app.services.store.interactions()
        assert rows[0]["prompt"] == "what is the battery level?"
        await pilot.press("f1")  # the dashboard heard the turn finish
        await pilot.pause()
        assert "last turn" in str(app.screen.query_one("#agent").render())
        await pilot.press("f3")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert app.screen.query_one(DataTable).row_count >= 1


async def test_chat_actuation_waits_for_the_operator(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f2")
        await pilot.pause()
        app.screen.query_one(Input).value = "send the robot to shipping"
        await pilot.press("enter")
        await wait_for(pilot, lambda: type(app.screen).__name__ == "ConfirmModal")
        assert sim_of(app).goal is None  # nothing moved yet
        await pilot.press("y")
        await app.workers.wait_for_complete()  # the turn, then its follow-up (fast sim time)
        await pilot.pause()
        assert sim_of(app).last_result.name == "shipping"
        log = " ".join(str(w.render()) for w in app.screen.query(".follow-up"))
        assert "↳ arrived: shipping (x 37." in log and "(for: send the robot to shipping)" in log
        await pilot.press("f1")  # the goal's event came while Chat was shown
        table = app.screen.query_one("#events", DataTable)
        await wait_for(
            pilot,
            lambda: any("accepted" in str(table.get_row_at(i)) for i in range(table.row_count)),
            what="the goal's 'accepted' event in the dashboard's events",
        )


async def test_an_unanswered_confirmation_closes_and_says_so(tmp_path):
    app = console(tmp_path, confirm_timeout_s=0.5)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f2")
        await pilot.pause()
        app.screen.query_one(Input).value = "send the robot to shipping"
        await pilot.press("enter")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert type(app.screen).__name__ == "ChatScreen"  # the dialog was closed
        assert sim_of(app).goal is None
        commands = app.services.store.commands_for(app.services.store.interactions()[0]["id"])
        assert commands[0]["executed"] == 0
        assert any("timed out" in n.title for n in app._notifications)


async def test_add_and_remove_a_location(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f4")
        await pilot.pause()
        await pilot.press("a")
        await pilot.pause()
        app.screen.query_one("#field-name", Input).value = "bay_9"
        app.screen.query_one("#field-x", Input).value = "12.5"
        await pilot.click("#ok")
        await pilot.pause()
        loc = app.services.store.get_location("bay_9")
        assert loc is not None and loc.x == 12.5 and loc.y == 3.0
        table = app.screen.query_one(DataTable)
        names = [loc.name for loc in app.screen.locations]
        table.move_cursor(row=names.index("bay_9"))
        await pilot.press("d")
        await pilot.pause()
        await pilot.press("y")
        await pilot.pause()
        assert app.services.store.get_location("bay_9") is None


async def test_bad_location_input_is_refused(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f4")
        await pilot.press("a")
        await pilot.pause()
        app.screen.query_one("#field-name", Input).value = "shipping"
        await pilot.click("#ok")
        await pilot.pause()
        assert len(app.services.store.list_locations()) == 6


async def test_teleop_drives_the_robot(tmp_path):
    app = console(tmp_path)
    sim = sim_of(app)
    sim.undock()
    sim.run_goal(60)
    x0 = sim.pose[0]
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f5")
        await pilot.pause()
        await pilot.press("plus", "plus")  # 0.8 m/s steps
        for _ in range(20):
            await pilot.press("s")  # backwards: the robot faces west, so +x
            sim.step(0.1)
        assert sim.pose[0] > x0 + 0.5
        sim.step(2.0)  # no more key presses: the command lapses, the base ramps down
        assert sim.speed() < 0.01


async def test_estop_works_from_any_screen_and_wins(tmp_path):
    app = console(tmp_path)
    sim = sim_of(app)
    async with app.run_test(size=SIZE) as pilot:
        sim.goto(37.6, 4.0, 0.0, "shipping")
        sim.step(3.0)
        await pilot.press("f2")  # the chat input has focus
        await pilot.pause()
        await pilot.press("ctrl+e")
        await pilot.pause()
        assert sim.e_stopped and sim.goal is None
        pose = sim.pose
        sim.step(2.0)
        assert math.dist(pose[:2], sim.pose[:2]) < 0.02
        await pilot.press("ctrl+r")
        await pilot.pause()
        await pilot.press("y")
        await pilot.pause()
        assert not sim.e_stopped


async def test_bench_screen_runs_and_ranks(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("f6")
        await pilot.pause()
        app.screen.query_one("#bench-models", Input).value = "rules"
        app.screen.query_one("#bench-limit", Input).value = "3"
        await pilot.press("ctrl+b")
        await app.workers.wait_for_complete()
        await pilot.pause()
        ranking = app.screen.query_one("#bench-ranking", DataTable)
        assert ranking.row_count == 1
        assert app.screen.query_one("#bench-runs", DataTable).row_count == 1
        app.screen.query_one("#bench-models", Input).value = "bogus:thing"
        await pilot.press("ctrl+b")
        await pilot.pause()
        assert app.screen.query_one("#bench-runs", DataTable).row_count == 1
        app.screen.query_one("#bench-models", Input).value = "rules"
        app.screen.query_one("#bench-protocol").value = "paper"  # needs a mock-response suite
        await pilot.press("ctrl+b")
        await pilot.pause()
        assert app.screen.query_one("#bench-runs", DataTable).row_count == 1
        assert any("mock responses" in n.message for n in app._notifications)


async def test_dashboard_says_when_the_model_server_is_down(tmp_path):
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    app = console(tmp_path, model=f"openai:m@http://127.0.0.1:{port}/v1")
    async with app.run_test(size=SIZE) as pilot:
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert "DOWN" in str(app.screen.query_one("#agent").render())


async def test_a_refused_plan_and_a_replaced_answer_are_shown_as_such(tmp_path):
    from tests.scripted_llm import ScriptedLLM

    llm = ScriptedLLM("openai")
    llm.replies = [  # tool mode; an unclear request is offered every tool
        '{"steps": [{"tool": "dock"}]}',
        '{"steps": [{"tool": "dock"}]}',  # the repair: still no
        '{"steps": [{"tool": "obstacles"}]}',
        "A forklift blocks the robot.",
    ]
    try:
        app = console(tmp_path, model=f"openai:scripted@{llm.url}")
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("f2")
            await pilot.pause()
            for request in ("hmm, the robot", "is anything blocking the robot?"):
                app.screen.query_one(Input).value = request
                await pilot.press("enter")
                await app.workers.wait_for_complete()
                await pilot.pause()
                assert type(app.screen).__name__ == "ChatScreen"  # no confirmation asked
            text = " ".join(str(w.render()) for w in app.screen.query("Static"))
            assert "⛔ refused by the intent gate" in text and "did not run this plan" in text
            assert "⚠ answer built from the results" in text and "0 obstacles detected" in text
            assert sim_of(app).docked()
    finally:
        llm.close()


async def test_a_request_sent_during_a_turn_waits_for_it_and_is_answered(tmp_path):
    from tests.scripted_llm import ScriptedLLM

    llm = ScriptedLLM("openai")
    held = threading.Event()  # the first plan is held until the second request is in

    def first_plan(_messages) -> str:
        held.wait(20)
        return '{"steps": [{"tool": "battery"}]}'

    llm.replies = [
        first_plan,
        "The battery is fine.",
        '{"steps": [{"tool": "where"}]}',
        "It is somewhere.",
    ]
    try:
        app = console(tmp_path, model=f"openai:scripted@{llm.url}")
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("f2")
            await pilot.pause()
            for request in ("what is the battery level?", "where is the robot?"):
                app.screen.query_one(Input).value = request
                await pilot.press("enter")
            assert "waiting for the turn before it" in " ".join(
                str(w.render()) for w in app.screen.query(".answer")
            )
            held.set()
            await app.workers.wait_for_complete()
            await pilot.pause()
            text = " ".join(str(w.render()) for w in app.screen.query(".answer"))
            assert "battery 85.0 %" in text and "x 1.15" in text and "thinking" not in text
            rows = app.services.store.interactions()
            assert [(r["prompt"], r["status"]) for r in reversed(rows)] == [
                ("what is the battery level?", "done"),
                ("where is the robot?", "done"),
            ]
    finally:
        llm.close()


async def test_the_command_palette_offers_the_consoles_own_commands(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        titles = [c.title for c in app.get_system_commands(app.screen)]
        for wanted in (
            "E-STOP",
            "Release the E-STOP",
            "Model: rules",
            "Reply mode: command",
            "Go to shipping",
            "Export logs as CSV",
        ):
            assert wanted in titles
        command = next(
            c for c in app.get_system_commands(app.screen) if c.title == "Model: embedded"
        )
        command.callback()
        await pilot.pause()
        await pilot.pause()
        assert type(app.screen).__name__ == "ChatScreen"
        assert app.services.endpoint.spec.raw == "embedded"
        go = next(c for c in app.get_system_commands(app.screen) if c.title == "Go to shipping")
        go.callback()
        await wait_for(pilot, lambda: type(app.screen).__name__ == "ConfirmModal")
        assert sim_of(app).goal is None
        await pilot.press("n")
        await app.workers.wait_for_complete()
        assert sim_of(app).goal is None


async def test_the_console_records_the_session_and_stops_from_the_palette(tmp_path):
    from astiop.recording import summary

    path = tmp_path / "console.mcap"
    app = console(tmp_path, record=path)
    async with app.run_test(size=SIZE) as pilot:
        assert app.recording.recorder is not None and "REC" in app.sub_title
        sim_of(app).step(2.0)  # the robot's clock moves on: new messages to record
        recorder = app.recording.recorder
        await wait_for(pilot, lambda: {"/robot_pose", "/battery_status"} <= recorder.counts.keys())
        stop = next(c for c in app.get_system_commands(app.screen) if c.title == "Stop recording")
        stop.callback()
        assert app.recording.recorder is None
        assert "Start recording" in [c.title for c in app.get_system_commands(app.screen)]
    counts = summary(path)
    assert counts.get("/robot_pose", 0) >= 1 and counts.get("/battery_status", 0) >= 1


async def test_the_maps_keepout_and_speed_zones_are_drawn_in_their_colours_and_named(tmp_path):
    from astiop.store import Store
    from astiop.widgets.map_view import KEEPOUT, SLOW

    store = Store(tmp_path / "console.db")  # the console's database (tui_helpers)
    store.add_zone("loading_bay", "keepout", [(31, 1), (38, 1), (38, 6), (31, 6)])
    store.add_zone("packing", "speed", [(2, 19), (6, 19), (6, 23), (2, 23)], 0.3)
    store.close()
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = app.screen.query_one(WarehouseMapView)
        text = map_text(view)
        assert "loading_bay" in text and "packing" in text
        assert "keepout" in text and "speed limit" in text  # the legend
        px = view._pixels
        s, x0, y0, top = view.frame

        def at(x, y):
            return px[top - 1 - math.floor((y - y0) * s), math.floor((x - x0) * s)]

        assert at(34.5, 3.5) == KEEPOUT and at(4.0, 21.0) == SLOW and at(25.0, 3.5) != KEEPOUT
