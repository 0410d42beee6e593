"""The Chat screen driven with Pilot: the conversation across /mode and /model, each turn
shown once, as it returns."""

from textual.widgets import Input

from tests.scripted_llm import ScriptedLLM
from tests.tui_helpers import console

SIZE = (120, 40)


async def send(app, pilot, text: str) -> None:
    app.screen.query_one(Input).value = text
    await pilot.press("enter")
    await app.workers.wait_for_complete()
    await pilot.pause()


def said(messages: list[dict]) -> list[tuple[str, str]]:
    return [(m["role"], m["content"]) for m in messages]


async def test_mode_and_model_switches_keep_the_conversation(tmp_path):
    llm, other = ScriptedLLM("openai"), ScriptedLLM("openai")
    llm.replies = [
        '{"steps": [{"tool": "battery"}]}',
        "The battery is at 85 %.",
        '{"commands": ["ros2 topic echo /robot_status --once"]}',
        "The robot is idle.",
    ]
    other.replies = ['{"commands": ["ros2 topic echo /robot_pose --once"]}', "Somewhere."]
    try:
        app = console(tmp_path, model=f"openai:scripted@{llm.url}")
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("f2")
            await pilot.pause()
            await send(app, pilot, "what is the battery level?")
            await send(app, pilot, "/mode command")
            await send(app, pilot, "what is it doing?")
            assert app.screen.agent.mode == "command"
            sent = said(llm.requests[2]["messages"])  # the plan of the turn after /mode
            assert ("user", "what is the battery level?") in sent
            assert ("assistant", "The battery is at 85 %.") in sent

            await send(app, pilot, f"/model openai:other@{other.url}")
            await send(app, pilot, "where is the robot?")
            assert app.services.endpoint.spec.raw == f"openai:other@{other.url}"
            sent = said(other.requests[0]["messages"])  # the new model hears both turns
            assert ("user", "what is the battery level?") in sent
            assert ("user", "what is it doing?") in sent
            assert len(llm.requests) == 4
            rows = app.services.store.interactions()
            assert [r["mode"] for r in reversed(rows)] == ["tool", "command", "command"]
    finally:
        llm.close()
        other.close()
