"""The console's mission panel: each step as it ended; escape cancels a running mission, p
pauses and resumes it, the palette's "Mission: …" commands do the same; a new mission while
one runs asks whether to replace it."""

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
    from tests.console.test_tui_approvals import asked

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


def answers(app) -> str:
    return " ".join(str(w.render()) for w in app.screen.query(".answer"))


async def test_a_new_mission_while_one_runs_asks_whether_to_replace_it(tmp_path):
    from textual.widgets import Input

    from tests.console.test_tui_approvals import asked

    app = console(tmp_path, settings=NO_ASKING)  # replacing is asked even so
    async with app.run_test(size=SIZE) as pilot:
        store = app.services.store
        runner = MissionRunner(app.services.gateway, store)
        first = runner.start([Step("wait", seconds=60), Step("undock")], "wait then undock")
        await pilot.press("f2")
        for answer in ("n", "y"):
            app.screen.query_one(Input).value = "go to shipping, then dock"
            await pilot.press("enter")
            await wait_for(pilot, lambda: asked(app) != "")
            question = asked(app)
            assert question.startswith(
                "Mission 1 is running on this robot (step 1 of 2 (wait 60 s), 0 done). Replace it?"
            ), question
            assert "1. go to shipping" in question and "2. dock" in question
            await pilot.press(answer)
            if answer == "n":
                await wait_for(pilot, lambda: "mission 1 goes on, not replaced" in answers(app))
                assert len(store.missions()) == 1, "nothing new stored"
                assert runner.running and app.services.gateway.backend.sim.goal is None
        await wait_for(pilot, lambda: "mission 2 started: 2 steps" in answers(app))
        assert "(it replaced mission 1)" in answers(app)
        row = store.mission(first)
        assert (row["status"], row["reason"]) == (
            "replaced",
            "replaced by mission 2 at step 1 of 2 (wait 60 s)",
        )
        await wait_for(pilot, lambda: store.mission(2)["status"] == "succeeded", 60)
        assert store.mission_steps(first)[1]["status"] == "pending", "its undock never ran"


async def test_the_palette_and_the_dashboard_key_pause_resume_and_cancel_a_mission(tmp_path):
    from textual.command import CommandInput, CommandList
    from textual.screen import Screen

    app = console(tmp_path, settings=NO_ASKING)
    async with app.run_test(size=SIZE) as pilot:
        store = app.services.store

        def titles_of(screen: Screen) -> list[str]:
            return [c.title for c in app.get_system_commands(screen)]

        def titles() -> list[str]:
            return titles_of(app.screen)

        def panel() -> str:
            return str(app.screen.query_one("#mission").render())

        assert not [t for t in titles() if t.startswith("Mission:")], "no mission, no command"
        # the palette as an operator uses it: ctrl+p, the command's name, enter
        dashboard = app.screen
        await pilot.press("ctrl+p")
        await wait_for(pilot, lambda: bool(app.screen.query(CommandInput)))
        # started with the palette open (its search asks for the commands as it is typed): the
        # first step outlasts the search and the keys on a loaded machine, the pause lands after it
        runner = MissionRunner(app.services.gateway, store)
        steps = [Step("wait", seconds=10), Step("wait", seconds=60), Step("undock")]
        mid = runner.start(steps, "wait, wait, undock")
        assert [t for t in titles_of(dashboard) if t.startswith("Mission:")] == [
            "Mission: pause",
            "Mission: cancel",
        ]
        app.screen.query_one(CommandInput).value = "Mission: pause"

        def hits() -> list[str]:
            found = app.screen.query(CommandList)
            if not found:
                return []
            return [str(o.prompt) for o in found.first().options]

        await wait_for(pilot, lambda: bool(hits()) and "Mission: pause" in hits()[0])
        await pilot.press("down")
        await wait_for(pilot, lambda: app.screen.query_one(CommandList).highlighted == 0)
        await pilot.press("enter")
        await wait_for(pilot, lambda: store.mission(mid)["status"] == "paused")
        await wait_for(pilot, lambda: "mission 1 paused: before step 2 of 3 (wait 60 s)" in panel())
        assert "p resumes" in panel() and store.mission_steps(mid)[1]["status"] == "pending"
        assert [t for t in titles() if t.startswith("Mission:")] == [
            "Mission: resume",
            "Mission: cancel",
        ]
        await pilot.press("p")  # the Dashboard's key: go on
        await wait_for(pilot, lambda: store.mission_steps(mid)[1]["status"] == "running")
        await wait_for(pilot, lambda: "▶ 2. wait 60 s" in panel())
        cancel = next(
            c for c in app.get_system_commands(app.screen) if c.title == "Mission: cancel"
        )
        cancel.callback()
        await wait_for(pilot, lambda: not runner.running)
        row = store.mission(mid)
        assert (row["status"], row["reason"]) == (
            "canceled",
            "canceled by the operator at step 2 of 3 (wait 60 s)",
        )
        assert store.mission_steps(mid)[2]["status"] == "pending"
