"""A watch said in the console's Chat is kept, and the console's sampler fires it as a
notification, the alert written once to the store."""

from tests.tui_helpers import ask, console, wait_for


def watch_alerts(store) -> list[dict]:
    """The watches' alerts (not the built-in ones a loaded machine may also raise)."""
    return [a for a in store.list_alerts() if a["kind"] == "watch"]


async def test_a_watch_said_in_the_chat_notifies_the_console_when_it_fires(tmp_path):
    app = console(tmp_path)  # the simulated battery is at 85 %
    async with app.run_test(size=(120, 40)) as pilot:
        said = await ask(app, pilot, "tell me when the battery is below 90 %")
        assert "Watch 1: I will tell you when the battery is below 90 % (once)." in said

        def alerted() -> list[str]:
            return [n.message for n in app._notifications if n.title == "alert"]

        def said_of_the_watch() -> list[str]:  # (a loaded machine may raise a built-in one too)
            return [a for a in alerted() if "90 %" in a]

        await wait_for(pilot, said_of_the_watch, what="the watch's notification")
        assert said_of_the_watch() == ["the battery is below 90 %: 85.00 %"]
        (alert,) = watch_alerts(app.services.store)
        assert alert["watch_id"] == 1 and alert["reading"] == "85.00 %"
        await pilot.press("f3")  # Logs: the alert among the turns and the robot's events
        logs = app.screen

        def logged() -> list[str]:
            rows = getattr(logs, "rows", [])
            return [r["summary"] for r in rows if r["summary"].startswith("[watch]")]

        await wait_for(pilot, lambda: bool(logged()), what="the alert in the Logs")
        assert logged() == ["[watch] the battery is below 90 %: 85.00 % (open)"]


async def test_a_reaction_said_in_the_chat_is_asked_armed_and_run_once(tmp_path):
    """ "..., then undock": the operator is asked with the condition and every step; no, and
    nothing is stored; yes, and the watch is armed; it fires and starts its mission once."""
    from textual.widgets import Input

    from tests.tui_helpers import sim_of

    app = console(tmp_path)  # asks before moving the robot; the battery at 85 %, docked
    async with app.run_test(size=(120, 40)) as pilot:
        store = app.services.store

        async def say(request: str, answer: str) -> str:
            await pilot.press("f2")
            await pilot.pause()
            app.screen.query_one(Input).value = request
            await pilot.press("enter")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "ConfirmModal")
            question = str(app.screen.query_one("Static").render())
            await pilot.press(answer)
            await app.workers.wait_for_complete()
            await pilot.pause()
            return question

        request = "tell me when the battery is below 90 %, then undock"
        question = await say(request, "n")
        assert question == (
            "When the battery is below 90 %, the robot will: 1. undock (once). Arm it?"
        )
        said = " ".join(str(w.render()) for w in app.screen.query(".answer"))
        assert "Not watched: the reaction was not approved; nothing was stored." in said
        assert store.list_watches() == [] and sim_of(app).docked()
        await say(request, "y")
        said = " ".join(str(w.render()) for w in app.screen.query(".answer"))
        assert (
            "Watch 1: I will tell you when the battery is below 90 % (once), then 1. undock."
            in said
        )
        assert " Armed, approved by " in said and "(the console's Chat)" in said
        await wait_for(pilot, lambda: len(store.missions()) == 1, what="the reaction's mission")
        (mission,) = store.missions()
        assert mission["source"] == "watch" and mission["request"].startswith("watch 1: ")
        await wait_for(pilot, lambda: not sim_of(app).docked(), what="the robot undocked")
        (alert,) = watch_alerts(store)
        assert alert["watch_id"] == 1 and store.watch(1)["armed"] == 0
        await pilot.pause(1.5)  # the watch reloaded: once, not again
        assert len(store.missions()) == 1 and len(watch_alerts(store)) == 1


async def test_with_confirmation_off_a_reaction_is_still_asked_and_an_unwatchable_one_not_run(
    tmp_path,
):
    """A reaction moves the robot later, when no one may be looking: asked even when the
    operator turned each command's confirmation off. One whose condition cannot be watched is
    refused whole, never planned to run now."""
    from tests.tui_helpers import sim_of

    app = console(tmp_path, settings={"robot": {"confirm_actuation": False}})
    async with app.run_test(size=(120, 40)) as pilot:
        said = await ask(app, pilot, "tell me when the lidar is dirty, then undock")
        assert "Not watched: no condition I can watch" in said and "nothing was stored" in said
        assert sim_of(app).docked() and app.services.store.list_watches() == []
        await pilot.press("f2")
        await pilot.pause()
        app.screen.query_one("Input").value = "tell me when the battery is below 90 %, then undock"
        await pilot.press("enter")
        await wait_for(pilot, lambda: type(app.screen).__name__ == "ConfirmModal", 30, "asked")
        await pilot.press("n")
        await app.workers.wait_for_complete()
        assert app.services.store.list_watches() == [] and sim_of(app).docked()
