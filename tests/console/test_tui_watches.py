"""A watch said in the console's Chat is kept, and the console's sampler fires it as a
notification, the alert written once to the store."""

from tests.tui_helpers import ask, console, wait_for


async def test_a_watch_said_in_the_chat_notifies_the_console_when_it_fires(tmp_path):
    app = console(tmp_path)  # the simulated battery is at 85 %
    async with app.run_test(size=(120, 40)) as pilot:
        said = await ask(app, pilot, "tell me when the battery is below 90 %")
        assert "Watch 1: I will tell you when the battery is below 90 % (once)." in said

        def alerted() -> list[str]:
            return [n.message for n in app._notifications if n.title == "alert"]

        await wait_for(pilot, lambda: alerted(), what="the watch's notification")
        assert alerted() == ["the battery is below 90 %: 85.00 %"]
        (alert,) = app.services.store.list_alerts()
        assert alert["watch_id"] == 1 and alert["reading"] == "85.00 %"
