"""The console approves or refuses an outside agent's actuation (astiop mcp asks through the
store): it says it is open, shows each request as the confirmation dialog does, and answers."""

from __future__ import annotations

import asyncio

from astiop.store import Store
from tests.tui_helpers import console, wait_for

SIZE = (120, 40)


def asked(app) -> str:
    """The open dialog's question, once it is on screen and composed; "" until then."""
    if type(app.screen).__name__ != "ConfirmModal":
        return ""
    found = app.screen.query("Static")
    return str(found.first().render()) if found else ""


GOTO = 'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"'


async def test_an_open_console_is_asked_and_its_answer_goes_back(tmp_path):
    app = console(tmp_path)
    server = Store(tmp_path / "console.db")  # the MCP server's own connection, as a process has
    async with app.run_test(size=SIZE) as pilot:
        await wait_for(pilot, server.console_open, what="the console's heartbeat")
        first = await asyncio.to_thread(server.request_approval, "claude-desktop", GOTO, "", 30)
        await wait_for(pilot, lambda: asked(app) != "")
        question = str(app.screen.query_one("Static").render())
        assert (
            "claude-desktop" in question and "/goto_position" in question and "shipping" in question
        )
        await pilot.press("y")
        await wait_for(pilot, lambda: server.approval(first)["status"] == "approved")
        second = await asyncio.to_thread(
            server.request_approval, "cursor", GOTO, "", 30, robot="astibot_4"
        )
        await wait_for(pilot, lambda: asked(app) != "")
        assert "moves astibot_4:" in str(app.screen.query_one("Static").render())  # a fleet's
        await pilot.press("n")
        await wait_for(pilot, lambda: server.approval(second)["status"] == "denied")
        assert app.services.gateway.backend.sim.goal is None, "the console itself sent nothing"
    assert not server.console_open(), "a closed console says so"
    server.close()


async def test_a_request_nobody_answers_closes_and_the_estop_answers_no(tmp_path):
    app = console(tmp_path)
    server = Store(tmp_path / "console.db")
    async with app.run_test(size=SIZE) as pilot:
        await wait_for(pilot, server.console_open, what="the console's heartbeat")
        late = await asyncio.to_thread(server.request_approval, "agent", GOTO, "", 3.0)
        await wait_for(pilot, lambda: asked(app) != "")
        await wait_for(pilot, lambda: type(app.screen).__name__ != "ConfirmModal", timeout=10)
        assert server.expire_approval(late) and server.approval(late)["status"] == "expired"
        held = await asyncio.to_thread(server.request_approval, "agent", GOTO, "", 30)
        await wait_for(pilot, lambda: asked(app) != "")
        await pilot.press("ctrl+e")  # the E-STOP answers any open question with "no"
        await wait_for(pilot, lambda: server.approval(held)["status"] == "denied")
    server.close()


async def test_an_mcp_client_actuation_is_approved_and_refused_in_the_console(tmp_path):
    """The SDK's client → `astiop mcp` (its own process) → the console on the same database:
    y lets the goal go to the robot, n refuses it and the client is told why."""
    import os
    import sys

    from mcp import Client, StdioServerParameters
    from mcp.types import Implementation

    env = {**os.environ, "ASTIOP_SIM__SPEED": "20", "ASTIOP_LLM__THREADS": "1"}
    args = ["-m", "astiop", "--db", str(tmp_path / "console.db"), "mcp"]
    params = StdioServerParameters(command=sys.executable, args=args, env=env)
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        server = Store(tmp_path / "console.db")
        await wait_for(pilot, server.console_open, what="the console's heartbeat")
        async with Client(params, client_info=Implementation(name="agent-x", version="1")) as c:

            async def ask(answer: str) -> tuple[bool, str]:
                call = asyncio.create_task(c.call_tool("go_to_location", {"name": "shipping"}))
                await wait_for(pilot, lambda: "agent-x" in asked(app))
                assert "shipping" in asked(app)
                await pilot.press(answer)
                result = await asyncio.wait_for(call, 30)
                return result.is_error, "\n".join(x.text for x in result.content)

            refused, text = await ask("n")
            assert refused and "denied by the operator" in text
            ok, text = await ask("y")
            assert not ok and "goal accepted: shipping" in text, text
        statuses = [r["status"] for r in server.db.query("SELECT status FROM approvals")]
        assert statuses == ["denied", "approved"]
        server.close()


async def test_a_request_answered_in_another_console_closes_here_and_is_answered_once(tmp_path):
    app = console(tmp_path)
    server = Store(tmp_path / "console.db")
    other = Store(tmp_path / "console.db")  # a second console (another terminal, a browser tab)
    async with app.run_test(size=SIZE) as pilot:
        await wait_for(pilot, server.console_open, what="the console's heartbeat")
        request = await asyncio.to_thread(server.request_approval, "agent", GOTO, "", 30)
        await wait_for(pilot, lambda: asked(app) != "")
        assert other.decide_approval(request, True, "console")
        await wait_for(pilot, lambda: type(app.screen).__name__ != "ConfirmModal")
        await pilot.press("n")  # too late to count: the dialog is gone, nothing is answered
        await pilot.pause(0.3)
        row = server.approval(request)
        assert (row["status"], row["decided_by"]) == ("approved", "console")
        said = [n.message for n in app._notifications]
        assert any("settled elsewhere" in m for m in said), said
    other.close()
    server.close()
