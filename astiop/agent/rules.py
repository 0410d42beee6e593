"""The rule-based planner: no LLM at all. The deterministic baseline ("traditional approaches"
in the paper) and the fallback when no model answers. Labelled `rules` everywhere.
"""

from __future__ import annotations

import difflib
import math
import re

from astiop.agent.summaries import summarize
from astiop.robot.output import Execution

GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition"
TRIGGER = "std_srvs/srv/Trigger"
_NUM = r"(-?\d+(?:\.\d+)?)"
_XY = re.compile(
    rf"\bx\s*=?\s*{_NUM}\s*,?\s*(?:and\s+)?y\s*=?\s*{_NUM}"
    rf"|\(?\s*{_NUM}\s*,\s*{_NUM}\s*\)?",
    re.I,
)
_THETA = re.compile(rf"(?:facing|heading|theta|angle)\s*(?:of\s*)?{_NUM}", re.I)

# (pattern, command) in priority order; the first match per clause wins
_READS = [
    (r"\b(e-?stop|stop|halt|freeze|abort|cancel)\b", f"ros2 service call /stop {TRIGGER}"),
    (r"\bundock\b|\boff the (dock|charger)\b", f"ros2 service call /undock {TRIGGER}"),
    (
        r"\b(dock|go charge|recharge|go to the charger|charging station)\b",
        f"ros2 service call /dock {TRIGGER}",
    ),
    (
        r"\bunload\b|\bdrop (it|the load)\b|\bhand over\b",
        f"ros2 service call /conveyor/unload {TRIGGER}",
    ),
    (r"\bload\b(?! sensor)|\bpick up\b", f"ros2 service call /conveyor/load {TRIGGER}"),
    (r"\bconveyor|load sensor|lamp|belt\b", "ros2 topic echo /conveyor/status --once"),
    (
        r"\bbattery|charge level|power level|voltage|how much charge\b",
        "ros2 topic echo /battery_status --once",
    ),
    (
        r"\bobstacle|blocking|blocked|in the way|around the robot|nearby|clear\b",
        "ros2 topic echo /obstacles --once",
    ),
    (r"\blidar|laser|scan\b", "ros2 topic echo /scan --once"),
    (r"\bdiagnos|health|error|fault|warning|motor\b", "ros2 topic echo /diagnostics --once"),
    (
        r"\blist (the |all )?(named )?locations|which locations|known locations|what locations\b",
        "ros2 service call /list_locations astiop_msgs/srv/ListLocations",
    ),
    (r"\bwhere\b|\bposition|location|pose|coordinates\b", "ros2 topic echo /robot_pose --once"),
    (r"\bstatus|state|doing|busy|idle\b", "ros2 topic echo /robot_status --once"),
    (r"\bspeed|velocity|moving|odometry\b", "ros2 topic echo /odom --once"),
]
_MOVE = re.compile(
    r"\b(go|send|drive|navigate|move|head|take|bring|return|inspect|visit|patrol)\b", re.I
)
_SPLIT = re.compile(
    r"\s*(?:,?\s*\band then\b|,?\s*\bthen\b|;|,?\s*\band\b(?=\s+(?:report|"
    r"check|tell|read|give|show|say|what|is|are|look|list|load|unload|dock|"
    r"come|go|return|drive|send)))\s*",
    re.I,
)


def _location(text: str, locations: list[str]) -> str | None:
    lowered = text.lower()
    words = re.sub(r"[^a-z0-9_ -]", " ", lowered)
    for name in sorted(locations, key=len, reverse=True):
        spaced = name.lower().replace("_", " ")
        if name.lower() in lowered or spaced in words:
            return name
    # "zone b" -> inspection_zone_b, "assembly" -> assembly_station, typos
    tokens = [t for t in words.split() if t not in {"the", "to", "go", "robot", "send", "drive"}]
    for name in locations:
        parts = name.lower().split("_")
        if len(parts) > 1 and " ".join(parts[-2:]) in " ".join(tokens):
            return name
    for token in tokens:
        for name in locations:
            if token in name.lower().split("_") and len(token) >= 5:
                return name
        close = difflib.get_close_matches(token, [n.lower() for n in locations], n=1, cutoff=0.8)
        if close:
            return next(n for n in locations if n.lower() == close[0])
    return None


def _clause_commands(clause: str, locations: list[str]) -> list[str]:
    if _MOVE.search(clause) and not re.search(r"\b(stop|dock|undock|charge)\b", clause, re.I):
        xy = _XY.search(clause)
        if xy:
            nums = [g for g in xy.groups() if g is not None]
            x, y = float(nums[0]), float(nums[1])
            th = _THETA.search(clause)
            theta = math.radians(float(th.group(1))) if th else 0.0
            return [f'{GOTO} "{{x: {x:.3f}, y: {y:.3f}, theta: {theta:.4f}}}"']
        name = _location(clause, locations)
        if name:
            return [f"{GOTO} \"{{name: '{name}'}}\""]
    for pattern, command in _READS:
        if re.search(pattern, clause, re.I):
            return [command]
    name = _location(clause, locations) if _MOVE.search(clause) else None
    return [f"{GOTO} \"{{name: '{name}'}}\""] if name else []


def plan(request: str, locations: list[str]) -> list[str]:
    commands: list[str] = []
    for clause in _SPLIT.split(request):
        if clause.strip():
            for c in _clause_commands(clause, locations):
                if c not in commands:
                    commands.append(c)
    return commands[:3]


def interpret(request: str, executions: list[Execution]) -> str:
    if not executions:
        return (
            "[rules] I only understand requests about the robot: position, battery, status, "
            "obstacles, diagnostics, the conveyor, going to a location, docking, stopping."
        )
    lines = [summarize(ex).split("\n", 1)[-1].strip() for ex in executions]
    return "[rules] " + " | ".join(lines)
