"""A subject's answer (`astiop.agent.subject`): the reads it takes, run through the gateway and
kept as the turn's commands, and the answer computed from them, saying how. A subject whose
reads lack what was asked says what was read and what is missing; a subject outside the robot
is declined in one line and nothing is read. The same for every model: a figure worked out
from several readings is computed, never left to a model's words."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

from astiop.agent import place_answers
from astiop.agent.roles import battery_percent, pose_of
from astiop.agent.subject import Subject
from astiop.ros2.roles import READ_ROLES
from astiop.transports.base import Execution

CAPABILITIES = (
    "I answer questions about this robot and run its commands. Ask about its readings "
    "({roles}), a field of one (the battery's temperature or current, the lidar's range, "
    "the heading), its parameters (top speed, tolerances), its ROS graph (nodes, topics, "
    "services, actions), the named places (how many, the nearest, how far, between two), "
    "why it is not moving, what is in front of it, and what it did (astiop's journal). Ask "
    "it to go to a place or coordinates, move a little, dock, undock, load, unload, save or "
    "list places, or stop."
)
OUTSIDE = (
    "That is outside the robot: I answer only about this robot (its readings, parameters, "
    "graph, places, activity and journal) and run its commands. Nothing was read."
)
UNKNOWN = (
    "I cannot tell what on the robot that asks about, so I read nothing. Ask about its "
    "readings, parameters, graph, places, activity or journal (`what can you do?` lists them)."
)
TECHNOLOGY = {1: "NiMH", 2: "LiON", 3: "LiPo", 4: "LiFe", 5: "NiCd", 6: "LiMn", 7: "ternary",
              8: "VRLA"}  # fmt: skip
HEALTH = {1: "good", 2: "overheated", 3: "dead", 4: "overvoltage", 5: "failed",
          6: "cold", 7: "watchdog timer expired", 8: "safety timer expired"}  # fmt: skip


@dataclass
class Reads:
    """The reads of one answer, run through the one door; each kept as a command of the turn."""

    gateway: Any
    ran: list[Execution] = field(default_factory=list)

    def run(self, command: str) -> Execution:
        ex = self.gateway.run(command, None)
        self.ran.append(ex)
        return ex

    def values(self, command: str) -> Any:
        ex = self.run(command)
        return ex.values if ex.executed and not ex.error else None

    def role(self, role: str) -> dict | None:
        name = self.gateway.profile.name(role)
        if not name:
            return None
        ex = self.run(f"ros2 topic echo {name} --once")
        return ex.values if ex.executed and not ex.error and isinstance(ex.values, dict) else None

    def role_ex(self, role: str) -> Execution | None:
        return next((e for e in reversed(self.ran) if e.role == role), None)

    def pose(self) -> tuple[float, float, float] | None:
        v = self.role("pose")
        return pose_of(v) if v else None


def answer(subject: Subject, reads: Reads, places: dict, store: Any) -> str:
    kind = subject.kind
    if kind == "outside":
        return OUTSIDE
    if kind == "unknown":
        return UNKNOWN
    if kind == "capabilities":
        profile = reads.gateway.profile  # every readable role the robot has (ros2/roles.py)
        roles = [r.name for r in READ_ROLES if r.readable and profile.has(r.name)]
        return CAPABILITIES.format(roles=", ".join(roles) or "none found yet")
    if kind == "journal":
        return journal(subject.hours, store)
    if kind == "graph":
        return graph(subject, reads)
    if kind == "places":
        return place_answers.answer(subject, reads, places)
    if kind == "parameter":
        return parameter(subject.what, reads)
    if kind == "activity":
        return why_still(reads)
    return field_answer(subject, reads)


# -- the graph ---------------------------------------------------------------------------
def graph(subject: Subject, reads: Reads) -> str:
    if subject.what in ("publishers", "subscribers"):
        return who_uses(subject, reads)
    if subject.what == "type":
        info = reads.values(f"ros2 topic info {subject.place}")
        if not isinstance(info, dict):
            return f"The robot's graph has no topic {subject.place}."
        return (
            f"{subject.place} carries {info.get('type')} ({info.get('publishers', 0)} "
            f"publisher(s), {info.get('subscribers', 0)} subscriber(s))."
        )
    names = reads.values(f"ros2 {subject.what[:-1]} list")
    if not isinstance(names, list):
        return f"I could not list the robot's {subject.what}: the read failed."
    names = sorted(str(n) for n in names)
    if subject.count:
        return f"The robot's graph has {len(names)} {subject.what}."
    shown = ", ".join(names[:40]) + (f" and {len(names) - 40} more" if len(names) > 40 else "")
    return f"The robot's graph has {len(names)} {subject.what}: {shown}."


MAX_NODES_ASKED = 25  # each node's info is one read: a large graph is not read whole


def who_uses(subject: Subject, reads: Reads) -> str:
    """The nodes that publish (or subscribe to) a topic, named by the robot's role for it
    ("the scan") or by its name, from each node's info."""
    said = subject.place or ""
    topic = reads.gateway.profile.name(said.strip("/")) or ("/" + said.strip("/"))
    nodes = reads.values("ros2 node list")
    if not isinstance(nodes, list):
        return "I could not list the robot's nodes: the read failed."
    side = "Publishers" if subject.what == "publishers" else "Subscribers"
    verb = "publishes" if subject.what == "publishers" else "subscribes to"
    found = []
    for node in sorted(nodes)[:MAX_NODES_ASKED]:
        info = reads.values(f"ros2 node info {node}")
        if isinstance(info, dict) and any(t == topic for t, _ in info.get(side) or []):
            found.append(node)
    asked = min(len(nodes), MAX_NODES_ASKED)
    if not found:
        return f"None of the {asked} nodes I asked {verb} {topic}."
    return f"{', '.join(found)} {verb} {topic} (from the info of {asked} nodes)."


# -- parameters --------------------------------------------------------------------------
def _tokens(name: str) -> set[str]:
    parts = set(name.lower().replace(".", "_").replace("/", "_").split("_")) - {""}
    aliases = {"vel": "speed", "velocity": "speed", "theta": "angular", "x": "linear"}
    return parts | {aliases[p] for p in parts if p in aliases}


def find_parameters(words: str, listing: dict) -> list[tuple[str, str]]:
    """The (node, parameter) pairs whose names share the most of `words`."""
    wanted = _tokens(words.replace(" ", "_"))
    scored = []
    for node, params in listing.items():
        for p in params or []:
            have = _tokens(p)
            score = len(wanted & have)
            if "angular" in have and "angular" not in wanted:
                score -= 2  # a top speed is not a turn rate
            if "min" in have and "max" in wanted:
                score -= 2
            scored.append((score, node, p))
    best = max((s for s, _, _ in scored), default=0)
    if best < max(1, min(2, len(wanted))):
        return []
    return [(n, p) for s, n, p in scored if s == best][:3]


def parameter(words: str, reads: Reads) -> str:
    listing = reads.values("ros2 param list")
    if not isinstance(listing, dict):
        return "I could not list the robot's parameters: the read failed."
    found = find_parameters(words, listing)
    named = [n for n in sorted(listing) if _tokens(n) & _tokens(words.replace(" ", "_"))]
    if not found and (named or not words):  # a node's parameters, or every node's: listed
        return (
            "; ".join(f"{n} has {', '.join(listing[n] or []) or 'none'}" for n in named or listing)
            + "."
        )
    if not found:
        nodes = ", ".join(sorted(listing)) or "none"
        return (
            f"The robot has no parameter for '{words}': I listed the parameters of its nodes "
            f"({nodes}) and none is named so."
        )
    said, read = [], 0
    for node, name in found:
        ex = reads.run(f"ros2 param get {node} {name}")
        v = ex.values if ex.executed and not ex.error else None
        value = v.get("value") if isinstance(v, dict) else None
        if value is not None:
            said.append(f"{node}'s {name} is {value}")
            read += 1
        else:  # listed, but its value did not come: said so, never a guess
            why = (ex.error or ex.reason or "no value came").split("\n")[0][:120]
            said.append(f"{node} lists {name}, but its value could not be read ({why})")
    how = " (its own parameter, read from the node)" if len(said) == 1 and read else ""
    return "; ".join(said) + how + "."


# -- what it is doing, and why it is still -----------------------------------------------
def why_still(reads: Reads) -> str:
    status = reads.role("status")
    moving = reads.role("odometry") if status is None else None
    if status is None and moving is None:
        return "The robot reports neither a status nor odometry: I cannot tell why it is still."
    if status is not None:
        speed = float(status.get("speed") or 0.0)
        reasons = []
        if status.get("e_stopped"):
            reasons.append("it is E-stopped (release the E-STOP to move it)")
        if status.get("fault"):
            reasons.append(f"it reports a fault: {status['fault']}")
        if status.get("docked"):
            state = status.get("state", "")
            reasons.append("it is docked" + (" and charging" if state == "charging" else ""))
        goal = status.get("active_goal") or ""
        if not goal:
            reasons.append("it has no goal (nothing asked it to go anywhere)")
        elif speed < 0.01:
            obstacles = reads.role("obstacles")
            n = len(obstacles.get("obstacles", []) or []) if obstacles else None
            blocked = f"; {n} obstacle(s) detected around it" if n else ""
            reasons.append(f"it has the goal '{goal}' but is not moving{blocked}")
        head = (
            f"The robot is moving at {speed:.2f} m/s (state {status.get('state', '?')}). "
            if speed >= 0.01
            else f"The robot's status says {status.get('state', '?')}, speed {speed:.2f} m/s: "
        )
        return head + ("; ".join(reasons) or "it reports no reason to be still") + "."
    twist = (moving.get("twist") or {}).get("twist") or {}
    lin = twist.get("linear") or {}
    speed = math.hypot(float(lin.get("x", 0.0)), float(lin.get("y", 0.0)))
    state = reads.gateway.state()
    why = "it is E-stopped by astiop" if state.e_stopped else "it reports no status saying why"
    return f"Its odometry says {speed:.2f} m/s; {why} (no goal is running from this console)."


# -- the journal -------------------------------------------------------------------------
def journal(hours: float, store: Any) -> str:
    if store is None:
        return "No journal is kept here (astiop runs without its store), so I cannot say."
    t1 = time.time()
    turns = [  # this very question is in the journal already: not something the robot did
        t for t in store.interactions_between(t1 - hours * 3600, t1) if t["status"] != "running"
    ]
    events = store.events_between(t1 - hours * 3600, t1)
    span = _span(hours)
    if not turns and not events:
        return f"astiop's journal holds nothing for the last {span}: no request and no event."
    said = [f"In the last {span} astiop's journal holds {len(turns)} request(s)"]
    ran = [c["command"] for t in turns for c in t["commands"] if c.get("executed")]
    if turns:
        last = "; ".join(f"'{t['prompt'][:60]}'" for t in turns[-3:])
        said.append(f" (the latest: {last}), {len(ran)} command(s) run")
    said.append(f" and {len(events)} robot event(s)")
    if events:
        said.append(": " + "; ".join(e["message"][:60] for e in events[-3:]))
    return "".join(said) + "."


def _span(hours: float) -> str:
    if hours < 1:
        return f"{round(hours * 60)} minutes"
    return "hour" if hours == 1 else f"{hours:g} hours"


# -- a field of a role -------------------------------------------------------------------
def field_answer(subject: Subject, reads: Reads) -> str:
    role, name = subject.what.split(".")
    latch = "engaged" if reads.gateway.latched else "released"
    if role == "status" and not reads.gateway.profile.has("status"):
        if name == "docked":
            return "The robot publishes no status, so it reports no docked state."
        return f"The robot reports no E-STOP state of its own; astiop's E-STOP latch is {latch}."
    values = reads.role(role)
    if values is None:
        if not reads.gateway.profile.has(role):
            return f"The robot publishes no {role} reading, so it reports no {_said(name)}."
        return f"I could not read the robot's {role}: the read failed."
    if role == "battery":
        ex = reads.role_ex("battery")
        return " ".join(_battery(subject, n, values, ex) for n in name.split(","))
    if role == "status" and name == "docked":
        docked = bool(values.get("docked"))
        return (
            f"The robot is {'docked' if docked else 'not docked'} (its status says docked "
            f"{str(docked).lower()}, state {values.get('state', '?')})."
        )
    if role == "status":
        held = bool(values.get("e_stopped"))
        return (
            f"The robot is {'E-stopped' if held else 'not E-stopped'} (its status says "
            f"e_stopped {str(held).lower()}); astiop's E-STOP latch is {latch}."
        )
    if role == "odometry":
        twist = (values.get("twist") or {}).get("twist") or {}
        wz = float((twist.get("angular") or {}).get("z", 0.0))
        return f"The robot turns at {wz:.2f} rad/s ({math.degrees(wz):.0f} °/s), by its odometry."
    if role == "pose":
        pose = pose_of(values)
        if pose is None:
            return "The robot's pose has no position I can read."
        if name in ("x", "y"):
            return f"The robot is at x {pose[0]:.2f} m, y {pose[1]:.2f} m in the map."
        deg = math.degrees(pose[2])
        return f"The robot faces {deg:.0f}° ({_compass(deg)}; 0° is the map's +x axis)."
    return " ".join(_scan(n, values) for n in name.split(","))


def _said(name: str) -> str:
    return name.replace("_", " ")


_num = place_answers.battery_figure


def _battery(subject: Subject, name: str, v: dict, ex: Execution | None) -> str:
    pct = battery_percent(ex) if ex is not None else None
    if name in ("time_to_full", "time_to_empty"):
        return place_answers.battery_time(name, v, pct)
    if name in ("temperature", "current", "voltage") and subject.thing not in ("battery", ""):
        return f"{_battery_reports(v)}; it reports no {subject.thing} {name}."
    if name == "technology":
        tech = TECHNOLOGY.get(int(v.get("power_supply_technology") or 0))
        where = f" ({v['location']})" if v.get("location") else ""
        if tech is None:
            return f"The battery does not say its chemistry{where}."
        return f"The battery is {tech}{where}."
    if name == "health":
        health = HEALTH.get(int(v.get("power_supply_health") or 0))
        return (
            f"The battery reports its health as {health}."
            if health
            else (f"{_battery_reports(v)}; it reports no health (unknown).")
        )
    if name == "charge_ah":
        charge, capacity = _num(v, "charge"), _num(v, "capacity")
        if not charge:
            return f"{_battery_reports(v)}; it reports no charge in Ah."
        of = f" of {capacity:.1f} Ah" if capacity else ""
        return f"The battery holds {charge:.1f} Ah{of} ({pct:.1f} %)."
    key = name
    value = _num(v, key)
    unit = {"temperature": "°C", "voltage": "V", "current": "A", "capacity": "Ah"}[name]
    if value is None or (name == "capacity" and value == 0.0):
        return f"{_battery_reports(v)}; it reports no battery {_said(name)}."
    extra = ""
    if name == "current":
        extra = " (charging)" if value > 0 else " (discharging)" if value < 0 else " (none flows)"
    if name == "capacity" and _num(v, "design_capacity"):
        extra = f" (designed for {_num(v, 'design_capacity'):g} Ah)"
    at = f", at {pct:.1f} % charge" if pct is not None else ""
    return f"The battery's {_said(name)} is {value:.2f} {unit}{extra}{at}."


def _battery_reports(v: dict) -> str:
    parts = []
    for key, unit, label in (("voltage", "V", "voltage"), ("current", "A", "current"),
                             ("charge", "Ah", "charge"), ("temperature", "°C", "temperature")):  # fmt: skip
        value = _num(v, key)
        if value is not None and not (key == "charge" and value == 0.0):
            parts.append(f"{value:.3g} {unit} {label}" if key == "temperature" else label)
    listed = (
        ", ".join(parts[:-1]) + (" and " if len(parts) > 1 else "") + (parts[-1] if parts else "")
    )
    return f"The robot reports the battery's {listed or 'percentage only'}"


def _compass(deg: float) -> str:
    names = ["east (+x)", "north-east", "north (+y)", "north-west", "west (-x)", "south-west",
             "south (-y)", "south-east"]  # fmt: skip
    return names[round((deg % 360) / 45) % 8]


def _scan(name: str, v: dict) -> str:
    if name == "frame":
        frame = (v.get("header") or {}).get("frame_id") or ""
        return f"The scan is in the '{frame}' frame." if frame else "The scan names no frame."
    if name in ("range_max", "range_min"):
        value = _num(v, name)
        word = "maximum" if name == "range_max" else "minimum"
        if value is None:
            return f"The laser scan reports no {word} range."
        return f"The lidar's {word} range is {value:g} m (from its scan's {name})."
    if name == "beams":
        return f"The lidar reports {len(v.get('ranges') or [])} beams per scan."
    if name == "rate":
        t = _num(v, "scan_time")
        if not t:
            return "The laser scan reports no scan time, so no rate."
        return f"The lidar scans at {1.0 / t:g} Hz (a scan every {t:g} s)."
    lo, hi = _num(v, "angle_min"), _num(v, "angle_max")
    if lo is None or hi is None:
        return "The laser scan reports no angles, so no field of view."
    return f"The lidar sees {math.degrees(hi - lo):.0f}° ({math.degrees(lo):.0f}° to {math.degrees(hi):.0f}°)."
