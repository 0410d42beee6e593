"""Short, factual summaries of command results for the interpretation call and the rules.

Small models copy numbers well and read long YAML badly; every number here comes from the
command's own values, so the answer cannot cite telemetry no command returned. Each says what
kind of fact it is: a reading the robot published (measured, with its age when it is old), what
astiop commanded, or what a service accepted (a goal accepted has not arrived).
"""

from __future__ import annotations

import math
import string
from typing import Any

from astiop.agent.roles import battery_percent, no_return, pose_of, role_of
from astiop.ros2 import grammar
from astiop.ros2.roles import ROLE_BY_NAME
from astiop.transports.base import Execution

# action_msgs/srv/CancelGoal.srv's return codes
# how a started goal is said: accepted as the robot answered, or sent on a goal topic (no answer)
GOAL_ACCEPTED, GOAL_SENT = "goal accepted", "goal sent"
CANCEL_CODES = {0: "accepted", 1: "rejected", 2: "unknown goal", 3: "goal already ended"}
STATUS_WORDS = {0: "unknown", 1: "charging", 2: "discharging", 3: "not charging", 4: "full"}
STALE_PERIODS = 2  # a reading older than this many of its topic's periods is said with its age


def summarize(ex: Execution) -> str:
    if not ex.executed:
        return f"{ex.command}\n  NOT RUN: {ex.reason}"
    if ex.error:
        return f"{ex.command}\n  FAILED: {ex.error}"
    body = _summary(ex, _values(ex))
    if body is not None and (age := stale_age(ex)) is not None:
        body += f" (read {age:.0f} s ago)"
    if body is None:
        body = ex.output.strip()
        if len(body) > 600:
            body = body[:600] + " ..."
    return f"{ex.command}\n  " + body.replace("\n", "\n  ")


def stale_age(ex: Execution) -> float | None:
    """The reading's age when it is older than STALE_PERIODS of its topic's periods."""
    if ex.age_s is None or ex.period_s is None or ex.period_s <= 0:
        return None
    return ex.age_s if ex.age_s > STALE_PERIODS * ex.period_s else None


def _deg(rad: float) -> float:
    return math.degrees(rad)


def _templated(role: str, v: dict) -> str | None:
    """The role's own summary (astiop.ros2.roles): the first of its templates its values fill,
    a field read as its size said as its bytes."""
    definition = ROLE_BY_NAME.get(role)
    if definition is None or not definition.summary:
        return None
    v = {**v, **{f"{f}_bytes": len(v[f] or []) for f in definition.sized if f in v}}
    for template in definition.summary:
        names = [name for _, name, _, _ in string.Formatter().parse(template) if name]
        if all(name in v for name in names):
            return template.format(
                **{n: "(not said)" if v[n] in ("", None) else v[n] for n in names}
            )
    return None


def _summary(ex: Execution, v: Any) -> str | None:
    if not isinstance(v, dict):
        return None
    command, provenance, role = ex.command, ex.provenance, role_of(ex)
    if role == "battery" and "percentage" in v:
        pct = battery_percent(ex)
        state = STATUS_WORDS.get(v.get("power_supply_status"), "unknown")
        state = "charging state unknown" if state == "unknown" else state
        return f"battery {pct:.1f} %, {v['voltage']:.2f} V, {v['current']:.2f} A, {state}"
    if role == "pose" and (pose := pose_of(v)) is not None:
        x, y, theta = pose
        return f"position x {x:.2f} m, y {y:.2f} m, heading {_deg(theta):.0f} deg"
    if role == "status" and "state" in v:
        docked = "docked, " if v.get("docked") else ""
        return (
            f"state {v['state']}, {docked}mode {v['mode']}, goal {v['active_goal'] or 'none'}, "
            f"fault {v['fault'] or 'none'}, speed {v['speed']:.2f} m/s"
        )
    if role == "obstacles" and "count" in v:
        if not v["count"]:
            return "0 obstacles detected"
        items = "; ".join(
            f"{o['kind']} at {o['distance']:.1f} m, bearing {_deg(o['bearing']):.0f} deg"
            for o in v["obstacles"][:5]
        )
        return f"{v['count']} obstacle(s) detected: {items}"
    if role == "scan" and "ranges" in v:
        hits = [(r, i) for i, r in enumerate(v["ranges"]) if not no_return(r, v)]
        if not hits:
            return "scan: nothing within range"
        r, i = min(hits)
        bearing = _deg(v["angle_min"] + i * v["angle_increment"])
        return f"scan of {len(v['ranges'])} beams: nearest return {r:.2f} m at {bearing:.0f} deg"
    if (templated := _templated(role, v)) is not None:
        return templated
    if role == "diagnostics" and "status" in v:
        levels = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}
        return "; ".join(
            f"{s['name']}: {levels.get(s['level'], s['level'])} ({s['message']})"
            for s in v["status"]
        )
    if role == "conveyor" and "loaded" in v:
        return (
            f"conveyor {'running' if v['running'] else 'stopped'}, "
            f"{'loaded' if v['loaded'] else 'empty'}, lamp {v['lamp']}"
        )
    if role in ("odometry", "pose") and "twist" in v:
        p = v["pose"]["pose"]["position"]
        t = v["twist"]["twist"]["linear"]
        return f"odometry x {p['x']:.2f} m, y {p['y']:.2f} m, speed {math.hypot(t['x'], t['y']):.2f} m/s"
    if "names" in v and "poses" in v:
        return "locations: " + ", ".join(
            f"{n} ({p['x']:.1f}, {p['y']:.1f})" for n, p in zip(v["names"], v["poses"])
        )
    if "return_code" in v and "goals_canceling" in v:  # action_msgs/srv/CancelGoal
        n, code = len(v["goals_canceling"] or []), v["return_code"]
        why = CANCEL_CODES.get(code, f"return code {code}")
        return f"navigation goals canceled: {n} ({why})"
    if "success" in v:
        word = (
            ("accepted" if provenance == "accepted" else "succeeded") if v["success"] else "FAILED"
        )
        return f"{word}: {v.get('message', '')}"
    if "published" in v or " pub " in command:
        return _published(v)
    if "status" in v and "accepted" in v:
        return f"navigation goal {v['status']}"
    return None


def _values(ex: Execution) -> Any:
    if ex.values is None and " topic pub " in ex.command:  # a CLI's pub prints, returns nothing
        return _pub_values(ex)
    return ex.values


def commanded_twist(ex: Execution) -> tuple[float, float, float] | None:
    """(vx, vy, wz) of the Twist a `topic pub` sent, or None for any other result."""
    v = _values(ex)
    if not isinstance(v, dict) or not ("published" in v or " pub " in ex.command):
        return None
    return _twist(v.get("twist"))


def _twist(twist: Any) -> tuple[float, float, float] | None:
    if not isinstance(twist, dict):
        return None
    lin, ang = twist.get("linear", {}), twist.get("angular", {})
    return float(lin.get("x", 0.0)), float(lin.get("y", 0.0)), float(ang.get("z", 0.0))


def directions(twist: tuple[float, float, float]) -> set[str]:
    """The directions a Twist commands: forward/backward, left/right (a strafe or a turn)."""
    vx, vy, wz = twist
    found = {"forward" if vx > 0 else "backward"} if vx else set()
    found |= {"left" if vy > 0 else "right"} if vy else set()
    return found | ({"left" if wz > 0 else "right"} if wz else set())


def _published(v: dict[str, Any]) -> str | None:
    """What astiop commanded on /cmd_vel, in words (the robot's motion is not measured here)."""
    twist = _twist(v.get("twist"))
    if twist is None:
        return None
    vx, vy, wz = twist
    moves = []
    if vx:
        moves.append(f"{'forward' if vx > 0 else 'backward'} {abs(vx):.2f} m/s")
    if vy:
        moves.append(f"{'left' if vy > 0 else 'right'} {abs(vy):.2f} m/s")
    if wz:
        moves.append(f"rotation {'left' if wz > 0 else 'right'} {abs(wz):.2f} rad/s")
    times = v.get("published")
    sent = f", sent {times} time(s)" if isinstance(times, int) else ""
    return f"commanded {', '.join(moves) or 'zero velocity (stop)'} on /cmd_vel{sent}"


def _pub_values(ex: Execution) -> dict[str, Any] | None:
    try:
        command = grammar.parse(ex.command)
    except grammar.CommandSyntaxError:
        return None
    twist = command.args.get("values")
    return {"published": ex.output.count("publishing #"), "twist": twist or {}}
