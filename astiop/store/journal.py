"""What happened: the agent's turns and their commands, robot events, the E-STOP latch."""

from __future__ import annotations

import contextlib
import json
import os
import time
from typing import Any


class JournalTables:
    # -- interactions, commands, events --------------------------------------------
    def start_interaction(self, *, model: str, mode: str, prompt: str, session: str = "") -> int:
        with self._tx():
            row = self.db["interactions"].insert(
                {
                    "session": session,
                    "started_at": time.time(),
                    "model": model,
                    "mode": mode,
                    "prompt": prompt,
                    "status": "running",
                    "pid": os.getpid(),
                }
            )
        return int(row.last_pk)

    def update_interaction(self, interaction_id: int, **fields: Any) -> None:
        if "raw_replies" in fields and not isinstance(fields["raw_replies"], str):
            fields["raw_replies"] = json.dumps(fields["raw_replies"])
        with self._tx():
            self.db["interactions"].update(interaction_id, fields)

    def add_command(self, interaction_id: int | None, **fields: Any) -> int:
        record = {"interaction_id": interaction_id, "created_at": time.time(), **fields}
        if "values" in record and not isinstance(record["values"], (str, type(None))):
            record["values"] = json.dumps(record["values"], default=str)
        with self._tx():
            return int(self.db["commands"].insert(record).last_pk)

    def add_event(
        self, kind: str, message: str, *, severity: str = "info", sim_t: float | None = None
    ) -> None:
        with self._tx():
            self.db["events"].insert(
                {
                    "t": time.time(),
                    "sim_t": sim_t,
                    "kind": kind,
                    "severity": severity,
                    "message": message,
                }
            )

    def keep_robot_events(self, events) -> None:
        """The robot's events (RobotEvent), in one write. It never raises: the record must
        never stop what is watching the robot (the console, `astiop record`)."""
        rows = [
            {"t": time.time(), "sim_t": e.t, "kind": e.kind, "severity": e.severity,
             "message": e.message}
            for e in events
        ]  # fmt: skip
        if rows:
            with contextlib.suppress(Exception), self._tx():
                self.db["events"].insert_all(rows)

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

    def latch_estop(self, who: str) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE estop SET engaged = 1, engaged_by = ?, engaged_at = ? WHERE id = 1",
                [who, time.time()],
            )

    def release_estop(self, who: str) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE estop SET engaged = 0, released_by = ?, released_at = ? WHERE id = 1",
                [who, time.time()],
            )

    def newest_interaction_id(self) -> int:
        return self.db.execute("SELECT max(id) FROM interactions").fetchone()[0] or 0

    def finished_interactions_after(self, interaction_id: int) -> list[dict[str, Any]]:
        """Turns that ended after `interaction_id`, with their commands (for recording)."""
        rows = list(
            self.db.query(
                "SELECT id, prompt, model, mode, answer, grounding, total_s, status "
                "FROM interactions WHERE id > ? AND status != 'running' ORDER BY id",
                [interaction_id],
            )
        )
        for row in rows:
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
        keys = ("prompt", "model", "mode", "answer", "grounding", "total_s", "status")
        with self._tx():
            row = {k: turn.get(k) for k in keys}
            row.update(session="replay", started_at=started_at, prompt=str(row["prompt"] or ""))
            row.update(model=str(row["model"] or ""), mode=str(row["mode"] or ""))
            interaction_id = int(self.db["interactions"].insert(row).last_pk)
            for seq, cmd in enumerate(turn.get("commands") or []):
                keep = ("command", "valid", "executed", "reason", "source")
                self.db["commands"].insert(
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
