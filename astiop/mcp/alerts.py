"""Alerts over MCP: the resource `astiop://alerts` (the open alerts, newest first), which a
client subscribes to — `resources/subscribe` on a 2025-era connection, `subscriptions/listen`
on a 2026-07-28 one — and is sent `notifications/resources/updated` when an alert opens or is
acknowledged by any process on this database; the tools `list_alerts` and `acknowledge_alert`.

The alerts are written by the consoles, `astiop watch run` and `serve` (the store keeps each
once); this server reads the store, so what every process fired reaches its clients."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import socket
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

import anyio
from mcp import types
from mcp.server.subscriptions import InMemorySubscriptionBus, ResourceUpdated
from mcp.shared.exceptions import MCPError
from mcp.types import INVALID_PARAMS

from astiop.mcp.tools import CALL, Refused
from astiop.watches.builtins import KINDS

log = logging.getLogger("astiop.mcp")
ALERTS_URI = "astiop://alerts"
POLL_S = 0.2  # an alert another process wrote is told to subscribers within this
OPEN_SHOWN = 200
MAX_LISTED = 500
ALERT_KINDS = ("watch", *KINDS)


def _alert_json(a: dict[str, Any]) -> dict[str, Any]:
    return {
        "id": a["id"], "robot": a["robot"], "kind": a["kind"], "message": a["message"],
        "reading": a["reading"], "reading_age_s": a["reading_age_s"], "fired_at": a["fired_at"],
        "watch_id": a["watch_id"], "acknowledged_by": a["acknowledged_by"],
        "acknowledged_at": a["acknowledged_at"],
    }  # fmt: skip


class AlertFeed:
    """The open alerts as a resource, its subscribers, and the watch on the store that tells
    them of each change."""

    def __init__(self, store, bus: InMemorySubscriptionBus):
        self.store = store
        self.bus = bus  # subscriptions/listen streams (2026-07-28)
        self.sessions: dict[int, Any] = {}  # resources/subscribe sessions (2025-era), by id
        self.version: tuple[int, float] | None = None

    # -- the resource and the tools ------------------------------------------------------------
    def open_alerts(self) -> str:
        rows = self.store.alerts_where(open_only=True, limit=OPEN_SHOWN)
        return json.dumps([_alert_json(a) for a in rows], indent=1)

    def list_alerts(
        self, robot: str = "", kind: str = "", open_only: bool = True, limit: int = 50
    ) -> dict:
        if kind and kind not in ALERT_KINDS:
            raise Refused(f"no alert kind '{kind[:64]}' (kinds: {', '.join(ALERT_KINDS)})")
        if isinstance(limit, bool) or not 1 <= limit <= MAX_LISTED:
            raise Refused(f"limit is 1 to {MAX_LISTED}")
        rows = self.store.alerts_where(
            robot or None, kind or None, open_only=open_only, limit=limit
        )
        return {"alerts": [_alert_json(a) for a in rows]}

    def acknowledge_alert(self, alert_id: int) -> dict:
        if self.store.alert(alert_id) is None:
            raise Refused(f"no alert {alert_id}")
        call = CALL.get(None)
        client = call.client if call is not None else "unknown"
        who = f"MCP client {client} on {socket.gethostname()} (pid {os.getpid()})"
        if not self.store.acknowledge_alert(alert_id, who):
            a = self.store.alert(alert_id) or {}
            raise Refused(
                f"alert {alert_id} was acknowledged already, by {a.get('acknowledged_by')}"
            )
        return _alert_json(self.store.alert(alert_id) or {})

    # -- resources/subscribe (2025-era connections) --------------------------------------------
    async def subscribe(self, ctx, params: types.SubscribeRequestParams) -> types.EmptyResult:
        if str(params.uri) != ALERTS_URI:
            raise MCPError(INVALID_PARAMS, f"only {ALERTS_URI} can be subscribed to")
        self.sessions[id(ctx.session)] = ctx.session
        return types.EmptyResult()

    async def unsubscribe(self, ctx, params: types.UnsubscribeRequestParams) -> types.EmptyResult:
        self.sessions.pop(id(ctx.session), None)
        return types.EmptyResult()

    # -- the watch on the store ----------------------------------------------------------------
    @asynccontextmanager
    async def watching(self, _server: Any) -> AsyncIterator[None]:
        """The server's lifespan: the store watched while it serves (as it is before the first
        request: a change after any subscription is told)."""
        with contextlib.suppress(Exception):  # a busy store: the watch's first look
            self.version = await anyio.to_thread.run_sync(self.store.alerts_version)
        async with anyio.create_task_group() as tg:
            tg.start_soon(self._watch)
            try:
                yield None
            finally:
                tg.cancel_scope.cancel()

    async def _watch(self) -> None:
        failing = False
        while True:
            await anyio.sleep(POLL_S)
            try:
                version = await anyio.to_thread.run_sync(self.store.alerts_version)
                failing = False
            except Exception as exc:  # noqa: BLE001 - a busy store: the next look
                if not failing:
                    log.warning("alerts not read: %s", exc)
                failing = True
                continue
            if self.version is not None and version != self.version:
                await self.changed()
            self.version = version

    async def changed(self) -> None:
        """Tell every subscriber that the open alerts changed (a closed session is dropped)."""
        await self.bus.publish(ResourceUpdated(uri=ALERTS_URI))
        for key, session in list(self.sessions.items()):
            try:
                await session.send_resource_updated(ALERTS_URI)
            except Exception:  # noqa: BLE001 - its client has gone
                self.sessions.pop(key, None)
