"""The console's mission panel: each step as it ended, and escape cancels a running mission."""

from astiop.missions.runner import MissionRunner
from astiop.missions.steps import Step
from tests.tui_helpers import ask, console, wait_for

SIZE = (120, 40)
NO_ASKING = {"robot": {"confirm_actuation": False}}


async def test_a_chat_sequence_runs_as_a_mission_shown_step_by_step(tmp_path):
    app = console(tmp_path, settings=NO_ASKING)
    async with app.run_test(size=SIZE) as pilot:
        said = await ask(app, pilot, "go to shipping, then inspection zone a, then dock")
        assert "mission 1 started: 3 steps" in said, said
        await pilot.press("f1")

        def panel() -> str:
            return str(app.screen.query_one("#mission").render())

        await wait_for(pilot, lambda: "mission 1 succeeded" in panel())
        text = panel()
        assert "✓ 1. go to shipping" in text and "✓ 2. go to inspection_zone_a" in text
        assert "✓ 3. dock" in text and "arrived: shipping" in text


async def test_escape_cancels_the_running_mission(tmp_path):
    app = console(tmp_path, settings=NO_ASKING)
    async with app.run_test(size=SIZE) as pilot:
        store = app.services.store
        runner = MissionRunner(app.services.gateway, store)
        mission_id = runner.start([Step("wait", seconds=60), Step("undock")], "wait then undock")

        def panel() -> str:
            return str(app.screen.query_one("#mission").render())

        await wait_for(pilot, lambda: "▶ 1. wait 60 s" in panel() and "· 2. undock" in panel())
        await pilot.press("escape")
        await wait_for(pilot, lambda: not runner.running)
        await wait_for(pilot, lambda: "canceled by the operator at step 1 of 2" in panel())
        assert store.mission(mission_id)["status"] == "canceled"
        assert "✗ 1. wait 60 s" in panel() and "· 2. undock" in panel()
        assert store.mission_steps(mission_id)[1]["status"] == "pending"  # never started


async def test_the_console_asks_once_for_the_whole_mission_every_step_shown(tmp_path):
    from tests.test_tui_approvals import asked

    app = console(tmp_path)  # confirmation on, as shipped
    async with app.run_test(size=SIZE) as pilot:
        from textual.widgets import Input

        await pilot.press("f2")
        app.screen.query_one(Input).value = "go to shipping, then inspection zone a, then dock"
        await pilot.press("enter")
        await wait_for(pilot, lambda: asked(app) != "")
        question = asked(app)
        assert "Start this mission of 3 steps?" in question
        assert "1. go to shipping" in question and "3. dock" in question
        await pilot.press("n")

        def answers() -> str:
            return " ".join(str(w.render()) for w in app.screen.query(".answer"))

        await wait_for(pilot, lambda: "Mission not started" in answers())
        assert app.services.store.missions() == [], "nothing stored as started"
        assert app.services.gateway.backend.sim.goal is None, "nothing was sent"
