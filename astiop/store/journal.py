"""What happened: the agent's turns and their commands, robot events, the E-STOP latch."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Collection
from typing import Any

from astiop import estop_sql
from astiop.store.connection import Connection, row_id


class JournalTables(Connection):
    # -- interactions, commands, events --------------------------------------------
    def start_interaction(
        self, *, model: str, mode: str, prompt: str, session: str = "", robot: str = ""
    ) -> int:
        with self._tx():
            row = self.db.table("interactions").insert(
                {
                    "session": session,
                    "started_at": time.time(),
                    "model": model,
                    "mode": mode,
                    "prompt": prompt,
                    "status": "running",
                    "pid": os.getpid(),
                    "robot": robot,
                }
            )
        return row_id(row.last_pk)

    def update_interaction(self, interaction_id: int, **fields: Any) -> None:
        if "raw_replies" in fields and not isinstance(fields["raw_replies"], str):
            fields["raw_replies"] = json.dumps(fields["raw_replies"])
        with self._tx():
            self.db.table("interactions").update(interaction_id, fields)

    def add_command(self, interaction_id: int | None, **fields: Any) -> int:
        record = {"interaction_id": interaction_id, "created_at": time.time(), **fields}
        if "values" in record and not isinstance(record["values"], (str, type(None))):
            record["values"] = json.dumps(record["values"], default=str)
        with self._tx():
            return row_id(self.db.table("commands").insert(record).last_pk)

    def add_event(
        self, kind: str, message: str, *, severity: str = "info", sim_t: float | None = None
    ) -> None:
        with self._tx():
            self.db.table("events").insert(
                {
                    "t": time.time(),
                    "sim_t": sim_t,
                    "kind": kind,
                    "severity": severity,
                    "message": message,
                }
            )

    def keep_robot_events(self, events, robot: str = "") -> str | None:
        """The robot's events (RobotEvent), in one write. It never raises: the record must
        never stop what is watching the robot (the console, `astiop record`); why it failed,
        for the caller to say."""
        rows = [
            {"t": time.time(), "sim_t": e.t, "kind": e.kind, "severity": e.severity,
             "message": e.message, "robot": robot}
            for e in events
        ]  # fmt: skip
        if rows:
            try:
                with self._tx():
                    self.db.table("events").insert_all(rows)
            except Exception as exc:  # noqa: BLE001 - said by the caller, never raised
                return f"robot events not kept: {exc}"
        return None

    def finish_command(self, command_id: int, **fields: Any) -> None:
        """A command journaled as sent (before the robot was told), completed with its result."""
        if "values" in fields and not isinstance(fields["values"], (str, type(None))):
            fields["values"] = json.dumps(fields["values"], default=str)
        with self._tx():
            self.db.table("commands").update(command_id, fields)

    def interactions(self, limit: int = 500) -> list[dict[str, Any]]:
        return list(self.db.query("SELECT * FROM interactions ORDER BY id DESC LIMIT ?", [limit]))

    def commands_for(self, interaction_id: int) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT * FROM commands WHERE interaction_id = ? ORDER BY seq, id", [interaction_id]
            )
        )

    def commands_by_interaction(self, ids: list[int]) -> dict[int, list[dict[str, Any]]]:
        found: dict[int, list[dict[str, Any]]] = {i: [] for i in ids}
        if ids:
            marks = ",".join("?" * len(ids))
            for row in self.db.query(
                f"SELECT * FROM commands WHERE interaction_id IN ({marks}) ORDER BY seq, id", ids
            ):
                found[row["interaction_id"]].append(row)
        return found

    # -- the E-STOP latch --------------------------------------------------------------
    def estop_latch(self) -> dict[str, Any] | None:
        """The latch while engaged (who, when), else None."""
        row = self.db.conn.execute(
            "SELECT engaged, engaged_by, engaged_at FROM estop WHERE id = 1"
        ).fetchone()
        if row and row[0]:
            return {"by": row[1], "at": row[2]}
        return None

    def estop_record(self) -> dict[str, Any]:
        """The latch's whole row: engaged, by, at, released_by, released_at."""
        row = self.db.conn.execute(
            "SELECT engaged, engaged_by, engaged_at, released_by, released_at FROM estop "
            "WHERE id = 1"
        ).fetchone()
        keys = ("engaged", "by", "at", "released_by", "released_at")
        return dict(zip(keys, row)) if row else {"engaged": 0}

    def robot_release(self, robot: str) -> dict[str, Any] | None:
        """The last release of one robot's own latch (by, at), else None."""
        row = self.db.conn.execute(
            "SELECT released_by, released_at FROM robot_estop_releases WHERE robot = ?", [robot]
        ).fetchone()
        return {"by": row[0], "at": row[1]} if row else None

    def robot_latch(self, robot: str) -> dict[str, Any] | None:
        """One robot's own latch while engaged (a fleet's robot, by its namespace), else None."""
        row = self.db.conn.execute(
            "SELECT engaged_by, engaged_at FROM robot_estops WHERE robot = ?", [robot]
        ).fetchone()
        return {"by": row[0], "at": row[1]} if row else None

    def latched_robots(self) -> list[str]:
        return [r[0] for r in self.db.conn.execute("SELECT robot FROM robot_estops ORDER BY 1")]

    def latch_robot(self, robot: str, who: str, at: float | None = None) -> bool:
        """Latch one robot's own E-STOP for a press made `at` (now); False if a release was
        made after it (nothing latched)."""
        at = time.time() if at is None else at
        with self._tx():
            released = self.robot_release(robot)
            if released is not None and released["at"] >= at:
                return False
            self.db.conn.execute(
                "INSERT OR IGNORE INTO robot_estops (robot, engaged_by, engaged_at) "
                "VALUES (?, ?, ?)",
                [robot, who, at],
            )
        return True

    def release_robot(self, robot: str, who: str = "", at: float | None = None) -> None:
        with self._tx():
            self.db.conn.execute("DELETE FROM robot_estops WHERE robot = ?", [robot])
            self.db.conn.execute(
                "INSERT OR REPLACE INTO robot_estop_releases (robot, released_by, released_at) "
                "VALUES (?, ?, ?)",
                [robot, who, time.time() if at is None else at],
            )

    def namespaces_driven(self, limit: int = 1000) -> list[str]:
        """The namespaces the last `limit` motion commands sent from here were under (a fleet's
        robots this database drove), latest first."""
        rows = self.db.conn.execute(
            "SELECT command FROM commands WHERE kind = 'actuate' AND executed = 1 "
            "ORDER BY id DESC LIMIT ?",
            [limit],
        ).fetchall()
        found: dict[str, None] = {}
        for (command,) in rows:
            name = next((t for t in command.split()[3:] if t.startswith("/")), "")
            if name.count("/") >= 2:  # its first name, under a namespace
                found.setdefault("/" + name.split("/")[1], None)
        return list(found)

    def latch_version(self) -> int:
        """SQLite's data_version on this thread's connection: it changes when another
        connection commits, so a watcher reads the latch only then (a few µs a look)."""
        return self.db.conn.execute("PRAGMA data_version").fetchone()[0]

    def latch_estop(self, who: str, at: float | None = None) -> bool:
        """Latch the E-STOP of every robot on this database for a press made `at` (now); False
        if a release was made after it (nothing latched)."""
        at = time.time() if at is None else at
        with self._tx():
            return self.db.conn.execute(estop_sql.LATCH, [who, at, at]).rowcount == 1

    def release_estop(self, who: str, at: float | None = None) -> None:
        with self._tx():
            self.db.conn.execute(estop_sql.RELEASE, [who, time.time() if at is None else at])

    def interaction_marks(self) -> tuple[int, list[int]]:
        """The newest turn's id and the ids of the turns still running, read together."""
        rows = self.db.execute(
            "SELECT id, status FROM interactions "
            "WHERE status = 'running' OR id = (SELECT max(id) FROM interactions)"
        ).fetchall()
        newest = max((i for i, _status in rows), default=0)
        return newest, [i for i, status in rows if status == "running"]

    def interactions_to_record(
        self, after_id: int, running: Collection[int] = ()
    ) -> list[dict[str, Any]]:
        """The turns after `after_id` and the turns `running` (seen running before), in one
        statement, so a turn missing from the list started after every turn in it: running
        ones with their status, ended ones with their commands too (for recording)."""
        ids = sorted(running)
        also = f" OR id IN ({','.join('?' * len(ids))})" if ids else ""
        rows = list(
            self.db.query(  # no ORDER BY: with it SQLite scans the table, without it looks up
                "SELECT id, prompt, model, mode, answer, grounding, total_s, status, robot "
                f"FROM interactions WHERE id > ?{also}",
                [after_id, *ids],
            )
        )
        rows.sort(key=lambda row: row["id"])
        for row in rows:
            if row["status"] != "running":
                row["commands"] = list(
                    self.db.query(
                        "SELECT command, valid, executed, reason, source FROM commands "
                        "WHERE interaction_id = ? ORDER BY seq",
                        [row["id"]],
                    )
                )
        return rows

    def add_recorded_interaction(self, turn: dict[str, Any], started_at: float) -> int:
        """A turn read back from a recording (replay), with its commands."""
        keys = ("prompt", "model", "mode", "answer", "grounding", "total_s", "status", "robot")
        with self._tx():
            row = {k: turn.get(k) for k in keys}
            row["robot"] = str(row["robot"] or "")
            row.update(session="replay", started_at=started_at, prompt=str(row["prompt"] or ""))
            row.update(model=str(row["model"] or ""), mode=str(row["mode"] or ""))
            interaction_id = row_id(self.db.table("interactions").insert(row).last_pk)
            for seq, cmd in enumerate(turn.get("commands") or []):
                keep = ("command", "valid", "executed", "reason", "source")
                self.db.table("commands").insert(
                    {"interaction_id": interaction_id, "created_at": started_at, "seq": seq}
                    | {k: cmd.get(k) for k in keep}
                )
        return interaction_id

    def events(self, limit: int = 500) -> list[dict[str, Any]]:
        return list(self.db.query("SELECT * FROM events ORDER BY id DESC LIMIT ?", [limit]))

    def interactions_between(self, t0: float, t1: float) -> list[dict[str, Any]]:
        """Turns started in [t0, t1] (wall time), oldest first, each with its commands."""
        rows = list(
            self.db.query(
                "SELECT * FROM interactions WHERE started_at BETWEEN ? AND ? ORDER BY started_at",
                [t0, t1],
            )
        )
        commands = self.commands_by_interaction([r["id"] for r in rows])
        for row in rows:
            row["commands"] = commands[row["id"]]
        return rows

    def events_between(self, t0: float, t1: float) -> list[dict[str, Any]]:
        return list(
            self.db.query("SELECT * FROM events WHERE t BETWEEN ? AND ? ORDER BY t", [t0, t1])
        )
