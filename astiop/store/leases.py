"""Who controls a shared robot: one lease per robot, held by one console or server at a time
and renewed by its heartbeat; a holder not heard for LEASE_TTL_S has let go (a process killed).
A lease is taken in one write (BEGIN IMMEDIATE), so two consoles never both hold it."""

from __future__ import annotations

import socket
import time
from typing import Any

from astiop.store.connection import Connection
from astiop.store.liveness import _alive

LEASE_TTL_S = 10.0
# a holder on this machine whose pid is gone has let go once it missed a heartbeat (2 s): not
# at once, for a live holder in another pid namespace (a container on the host's network has
# the host's name) still renews its lease
DEAD_AFTER_S = 3.0


def holder_alive(host: str, pid: int, seen_at: float) -> bool:
    """False when the holder was on this machine, its process is gone and its heartbeat missed
    (killed: its lease would otherwise hold for LEASE_TTL_S more)."""
    if host != socket.gethostname() or pid <= 0 or time.time() - seen_at < DEAD_AFTER_S:
        return True
    return _alive(pid)


class LeaseTables(Connection):
    def lease(self, robot: str) -> dict[str, Any] | None:
        """The robot's lease while its holder is live, else None."""
        row = self.db.conn.execute(
            "SELECT robot, token, who, host, pid, taken_at, seen_at, taken_from FROM leases "
            "WHERE robot = ? AND seen_at > ?",
            [robot, time.time() - LEASE_TTL_S],
        ).fetchone()
        keys = ("robot", "token", "who", "host", "pid", "taken_at", "seen_at", "taken_from")
        held = dict(zip(keys, row, strict=True)) if row else None
        if held is None or holder_alive(held["host"], held["pid"], held["seen_at"]):
            return held
        return None

    def take_lease(
        self, robot: str, token: str, who: str, host: str, pid: int, force: bool
    ) -> dict[str, Any] | None:
        """Take the robot's lease: free, stale or ours, or over a live holder with `force`.
        Returns the live holder it was refused by (None: taken)."""
        now = time.time()
        with self._tx():
            self.db.conn.execute("BEGIN IMMEDIATE")
            held = self.lease(robot)
            if held is not None and held["token"] != token and not force:
                return held
            taken_from = None
            if held is not None and held["token"] != token:
                taken_from = f"{held['who']} (pid {held['pid']} on {held['host']})"
            self.db.conn.execute(
                "INSERT INTO leases (robot, token, who, host, pid, taken_at, seen_at, taken_from)"
                " VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT(robot) DO UPDATE SET "
                "token = excluded.token, who = excluded.who, host = excluded.host, "
                "pid = excluded.pid, taken_at = excluded.taken_at, seen_at = excluded.seen_at, "
                "taken_from = excluded.taken_from",
                [robot, token, who, host, pid, now, now, taken_from],
            )
        return None

    def renew_lease(self, robot: str, token: str) -> bool:
        """The holder's heartbeat; False when the lease is no longer its own."""
        with self._tx():
            cur = self.db.conn.execute(
                "UPDATE leases SET seen_at = ? WHERE robot = ? AND token = ?",
                [time.time(), robot, token],
            )
        return cur.rowcount == 1

    def release_lease(self, robot: str, token: str) -> None:
        with self._tx():
            self.db.conn.execute("DELETE FROM leases WHERE robot = ? AND token = ?", [robot, token])
