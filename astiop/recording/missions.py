"""A mission's own record in a session: its start, each step's end (status, reason, the
robot's pose) and its end, read from the store as any process stored them (a mission may be
driven by another process than the recording one), each written once on /astiop/mission."""

from __future__ import annotations

import time
from typing import Any

TOPIC = "/astiop/mission"
POLL_S = 0.25  # the store is read at most this often (the recorder polls at 20 Hz)
LIVE = ("running", "paused", "queued")
SCHEMA = {
    "type": "object",
    "title": "astiop mission",
    "properties": {
        "event": {"enum": ["started", "step_ended", "paused", "resumed", "ended"]},
        "mission": {"type": "integer"},
        "text": {"type": "string"},
        "status": {"type": "string"},
        "step": {"type": "integer"},
        "steps_total": {"type": "integer"},
        "round": {"type": ["integer", "null"]},
        "label": {"type": "string"},
        "detail": {"type": ["string", "null"]},
        "pose": {"type": ["object", "null"]},
        "docked": {"type": ["boolean", "null"]},
        "reason": {"type": ["string", "null"]},
        "steps": {"type": "array"},
        "request": {"type": "string"},
        "until_stopped": {"type": "boolean"},
        "t": {"type": ["number", "null"]},
    },
}


class MissionLog:
    """What is new about the missions since the last look, as records to write."""

    def __init__(self, store):
        self.store = store
        self.since = time.time()  # missions that ended before the recording are not in it
        self._started: set[int] = set()
        self._ended: set[int] = set()
        self._ends: set[tuple[int, int, int, float]] = set()  # (mission, round, step, ended_at)
        self._status: dict[int, str] = {}
        self._looked = 0.0

    def poll(self) -> list[dict[str, Any]]:
        if self.store is None or time.monotonic() - self._looked < POLL_S:
            return []
        self._looked = time.monotonic()
        watching = sorted(self._started - self._ended)
        out: list[dict[str, Any]] = []
        for row, steps in self.store.missions_to_record(self.since, watching):
            out.extend(self._mission(row, steps))
        return out

    def _mission(self, row: dict, steps: list[dict]) -> list[dict[str, Any]]:
        mid, total = row["id"], len(steps)
        forever = bool(row["forever"])
        out = []
        if mid not in self._started:
            self._started.add(mid)
            labels = [s["label"] for s in steps]
            plan = "; ".join(f"{i}. {label}" for i, label in enumerate(labels, 1))
            plan += "; repeated until stopped" if forever else ""
            out.append(
                {
                    "event": "started",
                    "mission": mid,
                    "request": row["request"],
                    "steps": labels,
                    "steps_total": total,
                    "until_stopped": forever,
                    "t": row["created_at"],
                    "text": f"mission {mid} started: {total} steps — {plan}",
                }
            )
        for s in steps:
            key = (mid, s["round"], s["seq"], s["ended_at"])
            if s["ended_at"] is None or key in self._ends:
                continue
            self._ends.add(key)
            out.append(_step_end(row, s, total, forever))
        before, now = self._status.get(mid), row["status"]
        self._status[mid] = now
        where = f"step {row['step'] + 1} of {total}"
        if now == "paused" and before != "paused":
            out.append(_held(mid, "paused", f"mission {mid} paused before {where}", row))
        elif now == "running" and before == "paused":
            out.append(_held(mid, "resumed", f"mission {mid} goes on with {where}", row))
        if now not in LIVE and mid not in self._ended:
            self._ended.add(mid)
            reason = row["reason"] or ""
            out.append(
                {
                    "event": "ended",
                    "mission": mid,
                    "status": now,
                    "reason": reason,
                    "t": row["finished_at"],
                    "text": f"mission {mid} {now}: {reason}".rstrip(": "),
                }
            )
        return out


def _step_end(row: dict, s: dict, total: int, forever: bool) -> dict[str, Any]:
    mark = {"succeeded": "✓", "skipped": "–", "interrupted": "‖"}.get(s["status"], "✗")
    where = f"round {s['round']} step" if forever else "step"
    pose = None if s["x"] is None else {"x": s["x"], "y": s["y"], "theta": s["theta"]}
    return {
        "event": "step_ended",
        "mission": row["id"],
        "step": s["seq"] + 1,
        "steps_total": total,
        "round": s["round"] if forever else None,
        "label": s["label"],
        "status": s["status"],
        "detail": s["detail"],
        "pose": pose,
        "docked": None if s["docked"] is None else bool(s["docked"]),
        "t": s["ended_at"],
        "text": f"mission {row['id']}: {mark} {where} {s['seq'] + 1}/{total} {s['label']}: "
        f"{s['status']} — {s['detail'] or ''}".rstrip(" —"),
    }


def _held(mid: int, event: str, text: str, row: dict) -> dict[str, Any]:
    return {"event": event, "mission": mid, "step": row["step"] + 1, "text": text}
