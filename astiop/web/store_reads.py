"""What the page's header reads from astiop's database: the E-STOP latch (and latching it) and
the open alerts, on one thread of its own so a slow database never holds up the server."""

from __future__ import annotations

import asyncio
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

SHOWN_ALERTS = 5  # the newest open alerts the bell lists


class StoreReads:
    def __init__(self, db: Path):
        self.db = db
        self._thread = ThreadPoolExecutor(1, thread_name_prefix="astiop-serve-db")
        self._store: Any = None  # made on the thread, used only there

    def _on_thread(self) -> Any:
        if self._store is None:
            from astiop.store import Store

            self._store = Store(self.db)
        return self._store

    def _latch(self, who: str | None) -> dict:
        store = self._on_thread()
        if who is not None:
            store.latch_estop(who)
        return store.estop_latch() or {}

    async def latch(self, who: str | None = None) -> dict:
        """The latch as the database holds it; latched first when `who` is given."""
        return await asyncio.get_running_loop().run_in_executor(self._thread, self._latch, who)

    def _alerts(self) -> dict:
        store = self._on_thread()
        rows = store.alerts_where(open_only=True, limit=200)
        return {
            "open": len(rows),
            "newest": rows[0]["id"] if rows else 0,
            "alerts": [_said(row) for row in rows[:SHOWN_ALERTS]],
        }

    async def alerts(self) -> dict:
        """The open (unacknowledged) alerts: how many, and the newest few in words."""
        return await asyncio.get_running_loop().run_in_executor(self._thread, self._alerts)

    def close(self) -> None:
        self._thread.shutdown(wait=False)


def _said(row: dict) -> str:
    at = time.strftime("%H:%M:%S", time.localtime(row["fired_at"]))
    robot = f"{row['robot']}: " if row.get("robot") else ""
    return f"{at} {robot}{row['message']}"
