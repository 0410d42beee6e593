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
    "paused": "‖",
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
        "until_stopped": bool(row["forever"]),
        "round": row["round"],
        "pause_requested": bool(row["pause_requested"]) and row["status"] == "running",
        "replaced_by": row["replaced_by"],
        "created_at": row["created_at"],
        "finished_at": row["finished_at"],
        "steps": [_this_round(s, row["round"]) for s in steps],
    }


def _this_round(s: dict[str, Any], round_: int) -> dict[str, Any]:
    """A step row still holding an earlier round's end is pending in this round."""
    if s["round"] < round_:
        s = {**s, "status": "pending", "detail": None, "started_at": None, "ended_at": None}
        s.update(x=None, y=None, theta=None, docked=None)
    return {
        "n": s["seq"] + 1,
        "label": s["label"],
        "status": s["status"],
        "detail": s["detail"],
        "started_at": s["started_at"],
        "ended_at": s["ended_at"],
        "pose": None if s["x"] is None else {"x": s["x"], "y": s["y"], "theta": s["theta"]},
        "docked": None if s["docked"] is None else bool(s["docked"]),
    }


def summary(m: dict[str, Any]) -> str:
    """'mission 3 running: step 2 of 3 (go to inspection_zone_a), 1 done'."""
    head = f"mission {m['id']} {m['status']}"
    if m["status"] in ("running", "interrupted", "paused", "queued"):
        head += f": {where(m)}"
        if m["pause_requested"]:
            head += "; pauses at the end of this step"
    elif m["reason"]:
        head += f": {m['reason']}"
    return escape_controls(head)


def where(m: dict[str, Any]) -> str:
    """'round 2 (until stopped), step 1 of 2 (go to shipping), 0 done'; a paused mission is
    'before' the step it goes on with."""
    done = sum(s["status"] in ("succeeded", "skipped") for s in m["steps"])
    current = m["steps"][m["step"] - 1]["label"] if m["steps"] else "?"
    text = "before " if m["status"] == "paused" else ""
    text += f"step {m['step']} of {m['steps_total']} ({current}), {done} done"
    if m["until_stopped"]:
        text = f"round {m['round']} (until stopped), {text}"
    return text


def live_text(store: Store, mission_id: int) -> str:
    """'mission 2 is running on this robot (step 2 of 3 (go to shipping), 1 done)': the
    mission in the way of a new one."""
    m = as_json(store, mission_id)
    if m is None:
        return f"mission {mission_id} is running on this robot"
    return escape_controls(f"mission {m['id']} is {m['status']} on this robot ({where(m)})")


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
