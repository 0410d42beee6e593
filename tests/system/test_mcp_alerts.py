"""Alerts over MCP, with the SDK's own client over stdio against `astiop mcp`: the open alerts
are a resource a client subscribes to (`resources/subscribe` on a 2025-era connection,
`subscriptions/listen` on a 2026-07-28 one) and is told of when another process fires or
acknowledges one; `list_alerts` and `acknowledge_alert` are tools."""

from __future__ import annotations

import json
import os
import sys
import warnings

import anyio
from mcp import Client, StdioServerParameters
from mcp.types import Implementation, ResourceUpdatedNotification

from astiop.mcp.alerts import ALERTS_URI
from astiop.store import Store

ENV = {**os.environ, "ASTIOP_SIM__SPEED": "20", "ASTIOP_LLM__THREADS": "1"}
ME = Implementation(name="pytest", version="1")


def _client(db, **kwargs) -> Client:
    args = ["-m", "astiop", "--db", str(db), "mcp"]
    params = StdioServerParameters(command=sys.executable, args=args, env=ENV)
    return Client(params, client_info=ME, **kwargs)


def _fire(db, robot: str, kind: str, message: str, n: int) -> int:
    store = Store(db)  # another process's store: this test's own connection
    try:
        alert_id = store.fire_alert(f"{robot}/{kind}:{n}", robot=robot, kind=kind, message=message)
    finally:
        store.close()
    assert alert_id is not None
    return alert_id


async def _open(client) -> list[dict]:
    result = await client.read_resource(ALERTS_URI)
    return json.loads(result.contents[0].text)


async def test_a_subscribed_client_is_told_when_an_alert_opens_and_is_acknowledged(tmp_path):
    db = tmp_path / "mcp.db"
    Store(db).close()
    updated: list[str] = []

    async def on_message(message) -> None:
        if isinstance(message, ResourceUpdatedNotification):
            updated.append(str(message.params.uri))

    async def until(n: int) -> None:
        with anyio.fail_after(30):
            while len(updated) < n:
                await anyio.sleep(0.05)

    async with _client(db, mode="legacy", message_handler=on_message) as client:
        caps = client.session.server_capabilities  # type: ignore[union-attr]
        assert caps.resources is not None and caps.resources.subscribe is True
        listed = {str(r.uri) for r in (await client.list_resources()).resources}
        assert ALERTS_URI in listed
        assert await _open(client) == []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # deprecated as of 2026-07-28, served for 2025-era
            await client.subscribe_resource(ALERTS_URI)
        stop = _fire(db, "astibot_2", "estop", "E-STOP engaged by ana on bench (pid 7)", 1)
        await until(1)
        assert updated == [ALERTS_URI]
        (alert,) = await _open(client)
        assert alert["id"] == stop and alert["kind"] == "estop" and alert["acknowledged_by"] is None

        listed = await client.call_tool("list_alerts", {"robot": "astibot_2"})
        assert not listed.is_error
        assert [a["id"] for a in json.loads(listed.content[0].text)["alerts"]] == [stop]
        wrong = await client.call_tool("list_alerts", {"kind": "nonsense"})
        assert wrong.is_error and "no alert kind 'nonsense'" in wrong.content[0].text

        acked = await client.call_tool("acknowledge_alert", {"alert_id": stop})
        assert not acked.is_error, acked.content[0].text
        assert json.loads(acked.content[0].text)["acknowledged_by"].startswith("MCP client pytest")
        await until(2)  # acknowledged: the open alerts changed
        assert await _open(client) == []
        again = await client.call_tool("acknowledge_alert", {"alert_id": stop})
        assert again.is_error and "acknowledged already, by MCP client pytest" in (
            again.content[0].text
        )
    store = Store(db)
    try:
        assert store.alert(stop)["acknowledged_at"] is not None  # kept for every station
    finally:
        store.close()


async def test_a_listening_client_is_told_of_a_new_alert(tmp_path):
    db = tmp_path / "mcp.db"
    Store(db).close()
    async with _client(db) as client:
        async with client.listen(resource_subscriptions=[ALERTS_URI]) as sub:
            _fire(db, "astibot_1", "battery_low", "battery low: 18.0 % (below 20 %)", 1)
            with anyio.fail_after(30):
                async for event in sub:
                    assert getattr(event, "uri", None) == ALERTS_URI
                    break
        (alert,) = await _open(client)
        assert alert["kind"] == "battery_low"
