"""Missions and their steps: every SQL statement about them. A mission is `running` (or `paused`
between two steps) while a live process drives it; one whose process is gone is `interrupted`
at its step on the next open. Other processes ask (cancel, pause, resume, replace) through the
mission's row; the driving process reads the asks between and during steps.

A mission repeated until stopped reuses its step rows: each round starts them all `pending`
again and counts itself in `missions.round`, so the rows always say the current round."""

from __future__ import annotations

import os
import time
from typing import Any

from astiop.store.connection import Connection, row_id
from astiop.store.liveness import _alive

# a mission in one of these is over; `interrupted` may still be resumed or dropped
ENDED = ("succeeded", "failed", "canceled", "stopped", "dropped", "replaced")
LIVE = ("running", "paused", "queued")  # one of these per robot at a time
QUEUED_S = 60.0  # a queued mission no process claimed within this is interrupted


class MissionTables(Connection):
    def create_mission(
        self,
        robot: str,
        request: str,
        source: str,
        steps: list[tuple[str, str]],
        queued: bool = False,
        forever: bool = False,
    ) -> int:
        """A new mission, running in this process, or queued for another to claim (astiop
        chat --no-wait hands it to a process of its own); steps are (spec JSON, label)."""
        now = time.time()
        status, pid = ("queued", None) if queued else ("running", os.getpid())
        with self._tx():
            cur = self.db.conn.execute(
                "INSERT INTO missions (robot, request, source, status, pid, created_at, forever) "
                "VALUES (?, ?, ?, ?, ?, ?, ?)",
                [robot, request, source, status, pid, now, int(forever)],
            )
            mission_id = row_id(cur.lastrowid)
            self.db.conn.executemany(
                "INSERT INTO mission_steps (mission_id, seq, spec, label) VALUES (?, ?, ?, ?)",
                [(mission_id, seq, spec, label) for seq, (spec, label) in enumerate(steps)],
            )
        return mission_id

    def running_mission(self, robot: str) -> dict[str, Any] | None:
        """The mission a live process drives on this robot, if any."""
        self.mark_missions_interrupted()
        rows = list(
            self.db.query(
                "SELECT * FROM missions WHERE robot = ? AND status IN ('running', 'paused', 'queued') "
                "ORDER BY id DESC LIMIT 1",
                [robot],
            )
        )
        return rows[0] if rows else None

    def mission(self, mission_id: int) -> dict[str, Any] | None:
        if not 0 < mission_id < 2**63:  # SQLite's INTEGER: no such mission
            return None
        rows = list(self.db.query("SELECT * FROM missions WHERE id = ?", [mission_id]))
        return rows[0] if rows else None

    def latest_mission(self) -> dict[str, Any] | None:
        rows = list(self.db.query("SELECT * FROM missions ORDER BY id DESC LIMIT 1"))
        return rows[0] if rows else None

    def missions(self, limit: int = 20) -> list[dict[str, Any]]:
        return list(self.db.query("SELECT * FROM missions ORDER BY id DESC LIMIT ?", [limit]))

    def missions_to_record(
        self, since: float, watching: list[int]
    ) -> list[tuple[dict[str, Any], list[dict[str, Any]]]]:
        """For a session's recording: the live missions, those that ended since `since`, and
        those it watches (seen live, maybe interrupted since), each with its steps."""
        marks = ",".join("?" * len(watching)) or "NULL"
        rows = list(
            self.db.query(
                "SELECT * FROM missions WHERE status IN ('running', 'paused', 'queued') "
                f"OR finished_at >= ? OR id IN ({marks}) ORDER BY id",
                [since, *watching],
            )
        )
        return [(row, self.mission_steps(row["id"])) for row in rows]

    def mission_steps(self, mission_id: int) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT * FROM mission_steps WHERE mission_id = ? ORDER BY seq", [mission_id]
            )
        )

    def step_started(self, mission_id: int, seq: int) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE mission_steps SET status = 'running', started_at = ?, ended_at = NULL, "
                "detail = NULL, x = NULL, y = NULL, theta = NULL, docked = NULL, "
                "round = (SELECT round FROM missions WHERE id = ?) "
                "WHERE mission_id = ? AND seq = ?",
                [time.time(), mission_id, mission_id, seq],
            )
            self.db.conn.execute("UPDATE missions SET step = ? WHERE id = ?", [seq, mission_id])

    def step_ended(
        self,
        mission_id: int,
        seq: int,
        status: str,
        detail: str,
        pose: tuple[float, float, float] | None,
        docked: bool | None,
    ) -> None:
        x, y, theta = pose if pose is not None else (None, None, None)
        with self._tx():
            self.db.conn.execute(
                "UPDATE mission_steps SET status = ?, detail = ?, ended_at = ?, x = ?, y = ?, "
                "theta = ?, docked = ? WHERE mission_id = ? AND seq = ?",
                [status, detail, time.time(), x, y, theta, docked, mission_id, seq],
            )

    def finish_mission(self, mission_id: int, status: str, reason: str) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE missions SET status = ?, reason = ?, finished_at = ? WHERE id = ?",
                [status, reason, time.time(), mission_id],
            )

    def new_round(self, mission_id: int, round_: int) -> None:
        """A mission repeated until stopped begins its next round; each step row is taken over
        by this round when its step starts again (until then it holds the round before's end,
        which the views show as pending)."""
        with self._tx():
            self.db.conn.execute(
                "UPDATE missions SET round = ?, step = 0 WHERE id = ?", [round_, mission_id]
            )

    def mission_held(self, mission_id: int, paused: bool, next_step: int, reason: str) -> None:
        """Paused before `next_step` (the step it goes on with), or running again."""
        with self._tx():
            self.db.conn.execute(
                "UPDATE missions SET status = ?, step = ?, reason = ? "
                "WHERE id = ? AND status IN ('running', 'paused')",
                ["paused" if paused else "running", next_step, reason or None, mission_id],
            )

    def mission_requests(self, mission_id: int) -> dict[str, Any]:
        """What the operator asked of a mission: cancel, pause, and which mission replaces it."""
        row = self.db.conn.execute(
            "SELECT cancel_requested, pause_requested, replaced_by FROM missions WHERE id = ?",
            [mission_id],
        ).fetchone()
        if row is None:
            return {"cancel": False, "pause": False, "replaced_by": None}
        return {"cancel": bool(row[0]), "pause": bool(row[1]), "replaced_by": row[2]}

    def request_mission_pause(self, mission_id: int, pause: bool = True) -> str | None:
        """Ask the driving process to hold at the end of the current step (or to go on); the
        mission's status before, or None when there is no such mission."""
        self.mark_missions_interrupted()
        row = self.mission(mission_id)
        if row is None:
            return None
        if row["status"] in ("running", "paused"):
            with self._tx():
                self.db.conn.execute(
                    "UPDATE missions SET pause_requested = ? WHERE id = ?",
                    [int(pause), mission_id],
                )
        return row["status"]

    def request_mission_replace(self, mission_id: int, by: int) -> str | None:
        """Mission `by` replaces this one: its driving process ends it as replaced (a queued
        one, driven by nobody yet, is replaced at once). Its status before, or None."""
        self.mark_missions_interrupted()
        row = self.mission(mission_id)
        if row is None:
            return None
        with self._tx():
            if row["status"] in ("running", "paused"):
                self.db.conn.execute(
                    "UPDATE missions SET cancel_requested = 1, replaced_by = ? WHERE id = ?",
                    [by, mission_id],
                )
            elif row["status"] == "queued":
                self.db.conn.execute(
                    "UPDATE missions SET status = 'replaced', replaced_by = ?, finished_at = ?, "
                    "reason = ? WHERE id = ?",
                    [by, time.time(), f"replaced by mission {by} before it started", mission_id],
                )
        return row["status"]

    def request_mission_cancel(self, mission_id: int) -> str | None:
        """Ask the process driving a mission to cancel it; an interrupted one is dropped at
        once. The mission's status before, or None when there is no such mission."""
        self.mark_missions_interrupted()
        row = self.mission(mission_id)
        if row is None:
            return None
        with self._tx():
            if row["status"] in ("running", "paused"):
                self.db.conn.execute(
                    "UPDATE missions SET cancel_requested = 1 WHERE id = ?", [mission_id]
                )
            elif row["status"] in ("interrupted", "queued"):
                self.db.conn.execute(
                    "UPDATE missions SET status = 'dropped', finished_at = ?, "
                    "reason = 'dropped by the operator' WHERE id = ?",
                    [time.time(), mission_id],
                )
        return row["status"]

    def mission_cancel_requested(self, mission_id: int) -> bool:
        row = self.db.conn.execute(
            "SELECT cancel_requested FROM missions WHERE id = ?", [mission_id]
        ).fetchone()
        return bool(row and row[0])

    def claim_mission(self, mission_id: int, from_step: int) -> bool:
        """Resume an interrupted mission in this process; False if it is not interrupted."""
        with self._tx():
            cur = self.db.conn.execute(
                "UPDATE missions SET status = 'running', pid = ?, cancel_requested = 0, "
                "pause_requested = 0, reason = NULL, finished_at = NULL, step = ? "
                "WHERE id = ? AND status IN ('interrupted', 'queued')",
                [os.getpid(), from_step, mission_id],
            )
            if cur.rowcount != 1:
                return False
            self.db.conn.execute(
                "UPDATE mission_steps SET status = 'pending', detail = NULL, started_at = NULL, "
                "ended_at = NULL WHERE mission_id = ? AND seq >= ?",
                [mission_id, from_step],
            )
        return True

    def mark_missions_interrupted(self) -> None:
        """Missions left `running` by a process that is gone: `interrupted` at their step."""
        rows = self.db.conn.execute(
            "SELECT id, pid, step, status FROM missions WHERE status IN ('running', 'paused') "
            "OR (status = 'queued' AND created_at < ?)",
            [time.time() - QUEUED_S],
        ).fetchall()
        dead = [(i, step, st) for i, pid, step, st in rows if pid is None or not _alive(pid)]
        if not dead or self.readonly:
            return
        with self._tx():
            for mission_id, step, status in dead:
                when = "while paused before" if status == "paused" else "during"
                self.db.conn.execute(
                    "UPDATE missions SET status = 'interrupted', reason = ? WHERE id = ?",
                    [f"the astiop process ended {when} step {step + 1}", mission_id],
                )
                self.db.conn.execute(
                    "UPDATE mission_steps SET status = 'interrupted' "
                    "WHERE mission_id = ? AND status = 'running'",
                    [mission_id],
                )
