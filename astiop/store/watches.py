"""Watches and alerts. An alert is one event written once, whichever process saw it first: its
key is the event's name (robot/kind, or robot/watch:ID) and the episode that name is on; an
episode ends (the condition cleared) by one conditional update, so two processes that both see
the end move it on once."""

from __future__ import annotations

import math
import time
from typing import Any

from astiop.store.connection import Connection, row_id

SETTLE_S = 5.0
WATCH_COLUMNS = (
    "robot", "role", "field", "op", "threshold", "unit", "duration_s", "repeat", "reaction", "said",
    "place", "x", "y",
)  # fmt: skip


class WatchTables(Connection):
    # -- watches -------------------------------------------------------------------------
    def add_watch(self, **values: Any) -> int:
        cols = [c for c in WATCH_COLUMNS if c in values]
        marks = ", ".join("?" for _ in cols)
        with self._tx():
            cur = self.db.conn.execute(
                f"INSERT INTO watches ({', '.join(cols)}, created_at) VALUES ({marks}, ?)",
                [values[c] for c in cols] + [time.time()],
            )
            return row_id(cur.lastrowid)

    def list_watches(self, robot: str | None = None, armed_only: bool = False) -> list[dict]:
        where, args = [], []
        if robot is not None:
            where.append("robot = ?")
            args.append(robot)
        if armed_only:
            where.append("armed = 1")
        clause = f" WHERE {' AND '.join(where)}" if where else ""
        return list(self.db.query(f"SELECT * FROM watches{clause} ORDER BY id", args))

    def watch(self, watch_id: int) -> dict | None:
        rows = list(self.db.query("SELECT * FROM watches WHERE id = ?", [watch_id]))
        return rows[0] if rows else None

    def remove_watch(self, watch_id: int) -> bool:
        with self._tx():
            cur = self.db.conn.execute("DELETE FROM watches WHERE id = ?", [watch_id])
            return cur.rowcount == 1

    # -- alerts --------------------------------------------------------------------------
    def _episode(self, name: str) -> int:
        self.db.conn.execute(
            "INSERT OR IGNORE INTO alert_episodes (name, episode) VALUES (?, 0)", [name]
        )
        return self.db.conn.execute(
            "SELECT episode FROM alert_episodes WHERE name = ?", [name]
        ).fetchone()[0]

    def fire_alert(
        self,
        name: str,
        *,
        robot: str,
        kind: str,
        message: str,
        reading: str | None = None,
        reading_age_s: float | None = None,
        watch_id: int | None = None,
        disarm: bool = False,
        paired_with: str | None = None,
    ) -> int | None:
        """The new alert's id, or None when this event was written already (by any process).
        `disarm`: a once-only watch is disarmed with its alert; `paired_with`: the event that
        this one ends (contact regained ends contact lost), written only after it and keyed by
        its episode."""
        with self._tx():
            keyed_by = paired_with or name
            episode = self._episode(keyed_by)
            if paired_with is not None:
                opened = self.db.conn.execute(
                    "SELECT 1 FROM alerts WHERE event_key = ?", [f"{paired_with}#{episode}"]
                ).fetchone()
                if opened is None:
                    return None
            cur = self.db.conn.execute(
                "INSERT OR IGNORE INTO alerts (robot, kind, message, reading, reading_age_s, "
                "fired_at, watch_id, event_key) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [
                    robot, kind, message, reading, reading_age_s, time.time(), watch_id,
                    f"{name}#{episode}",
                ],
            )  # fmt: skip
            if cur.rowcount != 1:
                return None
            if disarm and watch_id is not None:
                self.db.conn.execute("UPDATE watches SET armed = 0 WHERE id = ?", [watch_id])
            return row_id(cur.lastrowid)

    def end_episode(self, name: str, settled: bool = False) -> None:
        """The condition `name` watches has cleared: its next event is a new one (once, however
        many processes say so). `settled`: only an alert fired SETTLE_S ago or more is ended (a
        process that first sees the condition clear may lag one that has just seen it hold)."""
        before = time.time() - SETTLE_S if settled else math.inf
        fired = self.db.conn.execute(  # a read first: most ends follow no alert, and a
            "SELECT 1 FROM alert_episodes e JOIN alerts a "  # write would wait for the lock
            "ON a.event_key = e.name || '#' || e.episode WHERE e.name = ? AND a.fired_at < ?",
            [name, before],
        ).fetchone()
        if fired is None:
            return
        with self._tx():
            self.db.conn.execute(
                "UPDATE alert_episodes SET episode = episode + 1 WHERE name = ? AND EXISTS "
                "(SELECT 1 FROM alerts WHERE event_key = alert_episodes.name || '#' || "
                "alert_episodes.episode AND fired_at < ?)",
                [name, before],
            )

    def list_alerts(
        self, robot: str | None = None, after_id: int = 0, limit: int = 200
    ) -> list[dict]:
        """Alerts after `after_id`, oldest first (the last `limit` of them)."""
        clause, args = "WHERE id > ?", [str(after_id)]
        if robot is not None:
            clause += " AND robot = ?"
            args.append(robot)
        rows = self.db.query(
            f"SELECT * FROM (SELECT * FROM alerts {clause} ORDER BY id DESC LIMIT ?) ORDER BY id",
            [*args, limit],
        )
        return list(rows)

    def alert(self, alert_id: int) -> dict | None:
        rows = list(self.db.query("SELECT * FROM alerts WHERE id = ?", [alert_id]))
        return rows[0] if rows else None

    def acknowledge_alert(self, alert_id: int, who: str) -> bool:
        with self._tx():
            cur = self.db.conn.execute(
                "UPDATE alerts SET acknowledged_by = ?, acknowledged_at = ? "
                "WHERE id = ? AND acknowledged_at IS NULL",
                [who, time.time(), alert_id],
            )
            return cur.rowcount == 1

    # -- what the built-in alerts read ---------------------------------------------------
    def missions_ended_badly(self, robot: str, limit: int = 20) -> list[dict]:
        """The robot's newest missions that failed or were interrupted."""
        return list(
            self.db.query(
                "SELECT id, status, reason, request FROM missions WHERE robot = ? AND status "
                "IN ('failed', 'interrupted') ORDER BY id DESC LIMIT ?",
                [robot, limit],
            )
        )

    def operator_stopped_since(self, t: float) -> bool:
        """Whether an astiop station on this database ran a stop or a cancel since `t`."""
        row = self.db.conn.execute(
            "SELECT 1 FROM commands WHERE created_at >= ? AND "
            "(command LIKE '%stop%' OR command LIKE '%cancel%') LIMIT 1",
            [t],
        ).fetchone()
        return row is not None

    # -- what the Alerts screen and MCP read -----------------------------------------------
    def alerts_where(
        self,
        robot: str | None = None,
        kind: str | None = None,
        open_only: bool = False,
        limit: int = 500,
    ) -> list[dict]:
        """The newest alerts first, filtered (`open_only`: not yet acknowledged)."""
        where, args = [], []
        if robot is not None:
            where.append("robot = ?")
            args.append(robot)
        if kind is not None:
            where.append("kind = ?")
            args.append(kind)
        if open_only:
            where.append("acknowledged_at IS NULL")
        clause = f" WHERE {' AND '.join(where)}" if where else ""
        rows = self.db.query(
            f"SELECT * FROM alerts{clause} ORDER BY id DESC LIMIT ?", [*args, limit]
        )
        return list(rows)

    def alerts_version(self) -> tuple[int, float]:
        """Changes whenever an alert is written or acknowledged, by any process."""
        row = self.db.conn.execute(
            "SELECT COALESCE(MAX(id), 0), COALESCE(MAX(acknowledged_at), 0) FROM alerts"
        ).fetchone()
        return int(row[0]), float(row[1])

    def alert_robots(self) -> list[str]:
        return [r[0] for r in self.db.conn.execute("SELECT DISTINCT robot FROM alerts ORDER BY 1")]
