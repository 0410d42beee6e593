"""A stored mission as the operator reads it (CLI, chat answers, MCP, the console's panel):
always from the store, so every view says what the steps' recorded ends say."""

from __future__ import annotations

from typing import Any

from astiop.bounded import escape_controls
from astiop.store import Store

MARKS = {
    "succeeded": "✓",
    "skipped": "–",
    "running": "▶",
    "pending": "·",
    "interrupted": "‖",
}


def mark(status: str) -> str:
    return MARKS.get(status, "✗")


def as_json(store: Store, mission_id: int) -> dict[str, Any] | None:
    row = store.mission(mission_id)
    if row is None:
        return None
    steps = store.mission_steps(mission_id)
    return {
        "id": row["id"],
        "robot": row["robot"],
        "request": row["request"],
        "status": row["status"],
        "step": row["step"] + 1,
        "steps_total": len(steps),
        "reason": row["reason"],
        "created_at": row["created_at"],
        "finished_at": row["finished_at"],
        "steps": [
            {
                "n": s["seq"] + 1,
                "label": s["label"],
                "status": s["status"],
                "detail": s["detail"],
                "started_at": s["started_at"],
                "ended_at": s["ended_at"],
                "pose": None if s["x"] is None else {"x": s["x"], "y": s["y"], "theta": s["theta"]},
                "docked": None if s["docked"] is None else bool(s["docked"]),
            }
            for s in steps
        ],
    }


def summary(m: dict[str, Any]) -> str:
    """'mission 3 running: step 2 of 3 (go to inspection_zone_a)'."""
    done = sum(s["status"] in ("succeeded", "skipped") for s in m["steps"])
    head = f"mission {m['id']} {m['status']}"
    if m["status"] in ("running", "interrupted"):
        current = m["steps"][m["step"] - 1]["label"] if m["steps"] else "?"
        head += f": step {m['step']} of {m['steps_total']} ({current}), {done} done"
    elif m["reason"]:
        head += f": {m['reason']}"
    return escape_controls(head)


def step_lines(m: dict[str, Any]) -> list[str]:
    lines = []
    for s in m["steps"]:
        line = f"{mark(s['status'])} {s['n']}. {s['label']}"
        if s["detail"]:
            line += f" — {s['detail']}"
        if s["started_at"] and s["ended_at"]:
            line += f" ({s['ended_at'] - s['started_at']:.1f} s)"
        lines.append(escape_controls(line))
    return lines


def done_text(m: dict[str, Any]) -> str:
    """What the robot did, from the recorded ends only ("what did the robot do?")."""
    ended = [s for s in m["steps"] if s["status"] not in ("pending", "running")]
    if not ended:
        return f"{summary(m)}; no step has ended yet"
    parts = [f"{s['n']}. {s['label']}: {s['status']} ({s['detail'] or 'no detail'})" for s in ended]
    return escape_controls(f"{summary(m)}. " + "; ".join(parts))
