"""What the operator asked for, read without a model, one clause at a time.

The rules planner plans from it; the gate (`astiop.agent.gate`) holds every model's plan to it.
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass, replace

from astiop.ros2.roles import ROLES

# the Trigger service that does each of these kinds (the rules, the tools and the gate use it)
SERVICE_FOR = {
    "stop": "/stop",
    "dock": "/dock",
    "undock": "/undock",
    "load": "/conveyor/load",
    "unload": "/conveyor/unload",
}
# kinds that make the robot do something; "read" and "list" only look
ACTUATING = frozenset(
    {"stop", "navigate", "dock", "undock", "load", "unload", "save", "motion", "configure"}
)

_NUM = r"(-?\d+(?:\.\d+)?)"
_XY = re.compile(
    rf"\bx\s*[=:]?\s*{_NUM}\s*(?:m\b)?\s*,?\s*(?:and\s+)?y\s*[=:]?\s*{_NUM}"
    rf"|\(?\s*{_NUM}\s*,\s*{_NUM}\s*\)?",
    re.I,
)
_THETA = re.compile(rf"\b(?:facing|heading|theta|angle|yaw)\s*(?:of\s*|=\s*)?{_NUM}", re.I)
_SPLIT = re.compile(
    r"[.?!;:]\s+|\s*(?:,?\s*\band then\b|,?\s*\bthen\b|,?\s*\bafter that\b|,?\s*\band\b(?=\s+(?:"
    r"report|check|tell|read|give|show|say|what|is|are|look|list|load|unload|offload|dock|undock|"
    r"come|go|return|drive|send|stop|save|turn|rotate)))\s*",
    re.I,
)
_POLITE = re.compile(
    r"^(?:(?:ok(?:ay)?|hey|hi|please|pls|kindly|now|robot|astibot|so)\b[,!]?\s*)+"
    r"|^(?:can|could|would|will)\s+(?:you|the robot|it|we)\s+(?:please\s+)?"
    r"|^i\s+(?:want|need|would like|'d like)\s+(?:you|the robot|it)\s+to\s+"
    r"|^(?:let's|lets)\s+",
    re.I,
)
_QUESTION = re.compile(
    r"^(?:is|are|was|were|does|do|did|has|have|what|what's|whats|where|where's|which|how|"
    r"who|when|why|any|anything|am)\b",
    re.I,
)
_NEGATED = re.compile(r"\b(?:don'?t|do not|never|no need to|without)\b", re.I)
_STOP = re.compile(
    r"\b(?:e-?stop|stop|halt|freeze|abort|cancel|emergency|hold (?:still|position))\b", re.I
)
_UNDOCK = re.compile(
    r"\bundock|\b(?:leave|exit|get off|back off|back out of|drive off|pull off|move off|"
    r"depart from|come off|disconnect from|unplug from)\b.*\b(?:dock|charger|charging)"
    r"|\bstop charging\b|\bunplug\b",
    re.I,
)
_DOCK = re.compile(
    r"\b(?:dock|recharge|charge|charging|charger|plug\b.{0,20}\bin)\b"
    r"(?!\s+(?:level|left|state))",
    re.I,
)
_UNLOAD = re.compile(
    r"\b(?:unload|unloading|offload|drop (?:it|off|the)|hand (?:it |the \w+ )?over|"
    r"put (?:it )?down|"
    r"release the (?:load|pallet|box|tote))\b",
    re.I,
)
_LOAD = re.compile(
    r"(?<!the )(?<!a )(?<!its )(?<!your )\b(?:load|(?:start|begin) loading|pick up|take on|"
    r"receive)\b(?!\s+sensor)",
    re.I,
)
_SAVE = re.compile(
    r"\b(?:save|remember|mark|store|record|bookmark|name|call)\b.*"
    r"\b(?:spot|place|position|location|pose|point|here|this)\b",
    re.I,
)
_CONFIGURE = re.compile(
    rf"\b(?:set|change|limit|cap|lower|raise)\b.*\b(?:speed|velocity|limit)\b.*?{_NUM}", re.I
)
_SAVE_NAME = re.compile(r"\b(?:as|called|named|name it|call it)\s+['\"]?([a-z][\w-]*)", re.I)
_LIST = re.compile(
    r"\blist\b.*\b(?:locations|places|spots|stations)|\b(?:which|what|known|named|saved|all)\s+"
    r"(?:named\s+)?(?:locations|places|spots|stations)\b|\blocations? (?:do you|does it) know",
    re.I,
)
_MOVE = re.compile(
    r"\b(?:go|goes|send|drive|navigate|move|head|take|bring|return|inspect|visit|patrol|travel|"
    r"proceed|get|come|relocate|reposition|roll)\b",
    re.I,
)
_PLACE_VERB = re.compile(
    r"\b(?:position|place|put|park)\b|\b(?:need|want)\s+(?:the robot|it)\s+(?:at|in|by)\b",
    re.I,
)
_MOTION = re.compile(
    r"\b(?:forward|forwards|ahead|backward|backwards|back up|reverse|strafe|sideways|rotate|"
    r"turn|spin|nudge|inch)\b|\bmove (?:left|right|back)\b",
    re.I,
)
_SLOW = re.compile(
    r"\b(?:slow|slowly|gently|carefully|a little|a bit|slightly|a touch|inch)\b", re.I
)

_READ_VERB = re.compile(
    r"^(?:report|tell|show|check|give|read|say|display|print|get me|let me know|look|"
    r"find out|monitor|see|list)\b",
    re.I,
)

# read topics: (pattern, topic), first match wins: each role's words, by rank (astiop.ros2.roles)
READS = [(r.words, r.key) for r in sorted((r for r in ROLES if r.words), key=lambda r: r.rank)]


@dataclass(frozen=True)
class Motion:
    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0
    seconds: float = 2.0


@dataclass(frozen=True)
class Intent:
    kind: str  # read | list | stop | navigate | dock | undock | load | unload | save | motion
    # | configure (place: the parameter, xy[0]: its value)
    # | none (explicitly not asked) | unknown
    clause: str = ""
    topic: str | None = None  # read: what it asks about
    place: str | None = None  # navigate: the named place; save: the new name
    xy: tuple[float, float] | None = None  # navigate: coordinates
    theta: float | None = None  # navigate: heading in radians
    motion: Motion | None = None

    @property
    def actuating(self) -> bool:
        return self.kind in ACTUATING


def clauses(request: str) -> list[str]:
    return [c.strip(" ,") for c in _SPLIT.split(request.strip()) if c and c.strip(" ,.?!")]


def classify(request: str, places: list[str]) -> list[Intent]:
    """One intent per clause of the request."""
    return [classify_clause(c, places) for c in clauses(request)]


def _strip(clause: str) -> tuple[str, bool]:
    text, polite = clause.strip(), False
    while True:
        m = _POLITE.match(text)
        if not m or not m.group(0):
            return text, polite
        polite = polite or bool(re.match(r"(can|could|would|will|i)\b", m.group(0), re.I))
        text = text[m.end() :].strip(" ,")


def classify_clause(clause: str, places: list[str]) -> Intent:
    text, asked = _strip(clause)
    question = not asked and (bool(_QUESTION.match(text)) or text.endswith("?"))
    if question:
        if _LIST.search(text):
            return Intent("list", clause)
        return Intent("read", clause, topic=_topic(text))
    if _READ_VERB.match(text):
        return (
            Intent("list", clause)
            if _LIST.search(text)
            else Intent("read", clause, topic=_topic(text))
        )
    if _NEGATED.search(text) and re.search(
        r"\b(?:move|go|drive|dock|undock|load|unload|stop|turn|leave)\b", text, re.I
    ):
        return Intent("none", clause)
    if m := _CONFIGURE.search(text):
        angular = bool(re.search(r"\b(?:angular|turn|rotation)", text, re.I))
        name = "max_angular_speed" if angular else "max_linear_speed"
        return Intent("configure", clause, place=name, xy=(float(m.group(1)), 0.0))
    if _UNDOCK.search(text):
        return Intent("undock", clause)
    if _STOP.search(text):
        return Intent("stop", clause)
    if _DOCK.search(text):
        return Intent("dock", clause)
    if _UNLOAD.search(text):
        return Intent("unload", clause)
    if _LOAD.search(text):
        return Intent("load", clause)
    if _SAVE.search(text):
        m = _SAVE_NAME.search(text)
        return Intent("save", clause, place=m.group(1) if m else None)
    if _LIST.search(text):
        return Intent("list", clause)
    if _MOVE.search(text) or _MOTION.search(text) or _PLACE_VERB.search(text) or _XY.search(text):
        target = _target(text, places)
        if target is not None:
            return replace(target, clause=clause)
        if _MOTION.search(text):
            return Intent("motion", clause, motion=_motion(text))
        if _MOVE.search(text):
            return Intent("navigate", clause)  # somewhere not named: the gate refuses goals
    topic = _topic(text)
    return Intent("read", clause, topic=topic) if topic else Intent("unknown", clause)


def _topic(text: str) -> str | None:
    for pattern, topic in READS:
        if re.search(rf"\b(?:{pattern})", text, re.I):
            return topic
    return None


def _target(text: str, places: list[str]) -> Intent | None:
    xy = _XY.search(text)
    if xy:
        nums = [float(g) for g in xy.groups() if g is not None]
        th = _THETA.search(text)
        theta = math.radians(float(th.group(1))) if th else None
        return Intent("navigate", xy=(nums[0], nums[1]), theta=theta)
    name = resolve_place(text, places)
    return Intent("navigate", place=name) if name else None


def _motion(text: str) -> Motion:
    slow = bool(_SLOW.search(text))
    speed, turn, seconds = (0.15, 0.3, 1.5) if slow else (0.3, 0.6, 2.0)
    lowered = text.lower()
    left = "left" in lowered
    if re.search(r"\b(?:rotate|turn|spin)\b", lowered):
        if re.search(r"\baround\b", lowered):
            return Motion(wz=turn, seconds=math.pi / turn)
        return Motion(wz=turn if left or "right" not in lowered else -turn, seconds=seconds)
    if re.search(r"\b(?:strafe|sideways)\b|\bmove (?:left|right)\b", lowered):
        return Motion(vy=speed if left else -speed, seconds=seconds)
    if re.search(r"\b(?:backward|backwards|back up|reverse|back)\b", lowered):
        return Motion(vx=-speed, seconds=seconds)
    return Motion(vx=speed, seconds=seconds)


_FILLER = {"the", "to", "go", "robot", "send", "drive", "at", "of", "over", "back", "head"}


def resolve_place(text: str, places: list[str]) -> str | None:
    """The named location a phrase means: exact, spaced ("cps storage"), its distinctive
    part ("zone b", "assembly") or a close spelling ("shiping")."""
    lowered = text.lower()
    words = re.sub(r"[^a-z0-9_ -]", " ", lowered)
    for name in sorted(places, key=len, reverse=True):
        spaced = name.lower().replace("_", " ")
        if re.search(rf"\b{re.escape(name.lower())}\b", lowered) or re.search(
            rf"\b{re.escape(spaced)}\b", words
        ):
            return name
    tokens = [t for t in words.split() if t not in _FILLER]
    joined = " ".join(tokens)
    for name in places:
        parts = name.lower().split("_")
        if len(parts) > 1 and re.search(rf"\b{re.escape(' '.join(parts[-2:]))}\b", joined):
            return name
    # the distinctive words a phrase shares with a name: "inspection area b", "assembly"
    scores = {name: _shared(tokens, name.lower().split("_")) for name in places}
    best = max(scores.values(), default=0)
    winners = [n for n, sc in scores.items() if sc == best]
    if best > 0 and len(winners) == 1:
        return winners[0]
    for token in tokens:
        close = difflib.get_close_matches(token, [n.lower() for n in places], n=1, cutoff=0.8)
        if close:
            return next(n for n in places if n.lower() == close[0])
    return None


_AREA_WORDS = {"zone", "area", "region", "section", "bay", "aisle", "station", "inspection"}


def _shared(tokens: list[str], parts: list[str]) -> int:
    score = 0
    for i, token in enumerate(tokens):
        if len(token) >= 5 and token in parts:
            score += 1
        elif len(token) <= 2 and token in parts and i and tokens[i - 1] in _AREA_WORDS:
            score += 1  # "zone b", "area a": a one-letter part only after an area word
    return score
