"""Approval of an outside agent's actuation by a person in an open console, through the store:
the MCP server asks and waits, a console that is open on the same database shows the request
and answers it. A console says it is open by a heartbeat."""

from __future__ import annotations

import os
import time
from typing import Any

from astiop.store.connection import Connection, row_id

CONSOLE_ALIVE_S = 3.0  # a console whose heartbeat is older than this is not open


class ApprovalTables(Connection):
    def console_heartbeat(self) -> None:
        """This process is an open console (called about once a second)."""
        now = time.time()
        with self._tx():
            self.db.conn.execute(
                "INSERT INTO consoles (pid, started_at, seen_at) VALUES (?, ?, ?) "
                "ON CONFLICT(pid) DO UPDATE SET seen_at = excluded.seen_at",
                [os.getpid(), now, now],
            )

    def console_closed(self) -> None:
        with self._tx():
            self.db.conn.execute("DELETE FROM consoles WHERE pid = ?", [os.getpid()])

    def console_open(self) -> bool:
        row = self.db.conn.execute(
            "SELECT COUNT(*) FROM consoles WHERE seen_at > ?", [time.time() - CONSOLE_ALIVE_S]
        ).fetchone()
        return bool(row and row[0])

    def request_approval(
        self, client: str, command: str, detail: str, timeout_s: float, robot: str = ""
    ) -> int:
        now = time.time()
        with self._tx():
            cur = self.db.conn.execute(
                "INSERT INTO approvals (client, command, detail, requested_at, expires_at, "
                "robot) VALUES (?, ?, ?, ?, ?, ?)",
                [client, command, detail, now, now + timeout_s, robot],
            )
            return row_id(cur.lastrowid)

    def approval(self, approval_id: int) -> dict[str, Any] | None:
        rows = list(self.db.query("SELECT * FROM approvals WHERE id = ?", [approval_id]))
        return rows[0] if rows else None

    def pending_approvals(self) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT * FROM approvals WHERE status = 'pending' AND expires_at > ? ORDER BY id",
                [time.time()],
            )
        )

    def decide_approval(self, approval_id: int, approved: bool, who: str) -> bool:
        """Approve or deny a pending request; False if it was no longer pending."""
        with self._tx():
            cur = self.db.conn.execute(
                "UPDATE approvals SET status = ?, decided_at = ?, decided_by = ? "
                "WHERE id = ? AND status = 'pending' AND expires_at > ?",
                ["approved" if approved else "denied", time.time(), who, approval_id, time.time()],
            )
            return cur.rowcount == 1

    def expire_approval(self, approval_id: int) -> bool:
        """Close a request nobody answered in time; False if it was answered meanwhile."""
        with self._tx():
            cur = self.db.conn.execute(
                "UPDATE approvals SET status = 'expired', decided_at = ? "
                "WHERE id = ? AND status = 'pending'",
                [time.time(), approval_id],
            )
            return cur.rowcount == 1
