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


def texts(app, selector: str) -> list[str]:
    return [str(w.render()) for w in app.screen.query(selector)]


async def test_a_turn_is_shown_once_and_the_other_screens_hear_of_it(tmp_path):
    llm = ScriptedLLM("openai")
    llm.replies = ['{"steps": [{"tool": "obstacles"}]}', "A forklift blocks the robot."]
    try:
        app = console(tmp_path, model=f"openai:scripted@{llm.url}")
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("f2")
            await pilot.pause()
            await send(app, pilot, "is anything blocking the robot?")
            for _ in range(3):  # the turn's broadcast has come and gone
                await pilot.pause()
            answers = [t for t in texts(app, ".answer") if "0 obstacles detected" in t]
            statuses = [t for t in texts(app, ".answer") if "· tool ·" in t]
            assert len(answers) == 1 and len(statuses) == 1, texts(app, ".answer")
            assert len(texts(app, ".grounding")) == 1
            assert len(texts(app, "CommandView")) == 1
            await pilot.press("f1")  # the dashboard heard the turn finish
            await pilot.pause()
            assert "last turn" in str(app.screen.query_one("#agent").render())
            await pilot.press("f2")
            await pilot.pause()
            assert len(texts(app, ".grounding")) == 1 and len(texts(app, "CommandView")) == 1
    finally:
        llm.close()


async def test_escape_cancels_the_running_request_and_the_waiting_ones(tmp_path):
    import threading

    llm = ScriptedLLM("openai")
    held = threading.Event()

    def held_plan(_messages) -> str:
        held.wait(20)
        return '{"steps": [{"tool": "battery"}]}'

    llm.replies = [held_plan]
    try:
        app = console(tmp_path, model=f"openai:scripted@{llm.url}")
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("f2")
            await pilot.pause()
            for request in ("battery level?", "where is the robot?", "is it docked?"):
                app.screen.query_one(Input).value = request
                await pilot.press("enter")
            for _ in range(200):  # until the first plan is asked for
                if llm.requests:
                    break
                await pilot.pause(0.05)
            assert len(llm.requests) == 1
            await pilot.press("escape")
            await app.workers.wait_for_complete()
            await pilot.pause()
            shown = texts(app, ".answer")
            assert sum("canceled: nothing more was sent" in t for t in shown) == 3, shown
            assert not any("thinking" in t or "waiting for the turn" in t for t in shown)
            rows = app.services.store.interactions()
            assert [(r["prompt"], r["status"]) for r in rows] == [("battery level?", "canceled")]
            held.set()
            llm.replies = ['{"steps": [{"tool": "where"}]}', "Somewhere."]
            await send(app, pilot, "where is the robot?")  # the next request runs at once
            assert any("x 1.15" in t for t in texts(app, ".answer"))
            assert [r["status"] for r in app.services.store.interactions()] == ["done", "canceled"]
    finally:
        held.set()
        llm.close()
