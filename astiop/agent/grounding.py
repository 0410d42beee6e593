"""Answers held to what the robot reported, sentence by sentence.

Every number, state word, arrival, count, load, health claim and place in a model's answer is
checked against this turn's command results. A sentence stays only if it states at least one
fact the results hold and nothing they do not (names of things absent from the results, such as
a service, a topic or an error the robot never mentioned, included). When no sentence stays, or
what stays leaves out what the robot reported, the answer is built from the results themselves
(`factual_answer`), and the reason is kept.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable

from astiop.agent.facts import GOAL, Facts
from astiop.agent.roles import battery_percent, pose_of, role_of
from astiop.agent.stated_numbers import (
    NUMBER,
    decimals,
    figures,
)
from astiop.agent.summaries import (
    stale_age,
    summarize,
)
from astiop.transports.base import Execution

_COUNT_WORDS = {
    "no": 0, "zero": 0, "one": 1, "a single": 1, "two": 2, "three": 3, "four": 4, "five": 5,
    "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10,
}  # fmt: skip
_COUNTED = r"(?:obstacles?|objects?|people|persons?|pallets?|forklifts?|things?|items?)"
_NEGATION = re.compile(
    r"\b(?:not|n't|no|never|without|yet to|nor|isn't|aren't|hasn't)\W+(?:\w+\W+){0,2}$", re.I
)
# claim word -> the fact words that support it
STATE_CLAIMS: dict[str, set[str]] = {
    "idle": {"idle"},
    "navigating": {"navigating", "moving"},
    "on its way": {"navigating", "moving"},
    "en route": {"navigating", "moving"},
    "moving": {"navigating", "moving", "docking", "undocking"},
    "driving": {"navigating", "moving", "docking", "undocking"},
    "stopped": {"stopped"},
    "stationary": {"stopped"},
    "standing still": {"stopped"},
    "docked": {"docked"},
    "docking": {"docking"},
    "undocked": {"undocked"},
    "off the dock": {"undocked"},
    "undocking": {"undocking"},
    "charging": {"charging"},
    "discharging": {"discharging"},
    "fully charged": {"full"},
    "blocked": {"blocked", "obstacles"},
    "obstructed": {"blocked", "obstacles"},
    "e-stopped": {"e_stopped"},
    "emergency stop": {"e_stopped"},
    "fault": {"fault"},
    "faulted": {"fault"},
    "error": {"fault", "error"},
    "loaded": {"loaded"},
    "empty": {"empty"},
    "unloaded": {"empty"},
    "running": {"running"},
    "healthy": {"healthy"},
    "no faults": {"healthy"},
    "no errors": {"healthy"},
    "nominal": {"healthy"},
    "clear": {"clear"},
    "no obstacles": {"clear"},
    "nothing blocking": {"clear"},
    "succeeded": {"succeeded"},
    "successfully": {"succeeded"},
    "accepted": {"accepted", "succeeded"},
    "canceled": {"canceled"},
    "cancelled": {"canceled"},
    "turning": {"moving", "navigating", "docking", "undocking"},
    "rotating": {"moving", "navigating", "docking", "undocking"},
    "strafing": {"moving"},
    "loading": {"loading"},
    "unloading": {"unloading"},
}
ARRIVAL = re.compile(
    r"\b(?:arrived|arrives|has reached|reached|reaches|is now at|is at the|made it to|got to|"
    r"gets to|is there|has gotten to|"
    r"successfully navigated|completed the (?:trip|route|navigation)|finished navigating)\b",
    re.I,
)
OBSTACLE_KINDS = re.compile(
    r"\b(?:person|people|human|worker|pallet|forklift|box|drone|cart|vehicle|robot arm|"
    r"wall of boxes|crate|animal)s?\b",
    re.I,
)
# what names a thing: a ROS name, a CamelCase identifier, a code with letters and digits
_NAMED = re.compile(
    r"(?<![\w/])/[A-Za-z_][\w/]*|\b[A-Z][a-z0-9]+(?:[A-Z][a-z0-9]*)+\b|"
    r"\b(?=[A-Za-z-]*\d)(?=[\d-]*[A-Za-z])[A-Za-z][\w-]*\d[\w-]*\b"
)
_DIRECTIONS = {
    "left": "left", "right": "right", "forward": "forward", "forwards": "forward",
    "backward": "backward", "backwards": "backward", "clockwise": "right",
    "counterclockwise": "left", "anticlockwise": "left",
}  # fmt: skip
_QUANTITY_NOUNS = {"m/s": "a speed", "V": "a voltage", "deg": "an angle", "%": "a charge"}
_CLAUSE = re.compile(r"(;\s+|,\s+(?:and|but)\s+)")  # a sentence's parts, kept with their joints
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=\S)")
REPLY_CUT = {"length": "it ran past its token cap", "repetition": "it repeated itself",
             "deadline": "it ran past its deadline"}  # fmt: skip


def _negated(answer: str, start: int, end: int | None = None) -> bool:
    """'not charging', 'no fault', or 'fault none' as the summaries write it."""
    after = answer[end : end + 8] if end is not None else ""
    return bool(_NEGATION.search(answer[max(0, start - 40) : start])) or bool(
        re.match(r"\W*none\b", after)
    )


def unsupported(answer: str, facts: Facts) -> str | None:
    """The first claim of `answer` the results do not support, as a reason; None if none."""
    for m in NUMBER.finditer(answer):
        claim = float(m.group())
        tol = 10.0 ** -decimals(m.group()) + 1e-9
        if not any(abs(claim - f) <= tol for f in facts.numbers):
            return f"it states {m.group()}, which no result reported"
    for value, unit, called in figures(answer):
        if unit and not _reported_as(value, unit, facts):
            return f"it states {value:g} {unit}, which no result reported"
        if unit and called and called != unit:
            return f"it calls {value:g} {unit} {_QUANTITY_NOUNS[called]}"
    if facts.directions is not None:
        for m in re.finditer(rf"\b({'|'.join(_DIRECTIONS)})\b", answer, re.I):
            direction = _DIRECTIONS[m.group(1).lower()]
            if direction not in facts.directions and not _negated(answer.lower(), m.start()):
                return f"it says {m.group(1)}, but astiop commanded {', '.join(sorted(facts.directions)) or 'no motion'}"
    for m in re.finditer(rf"\b({'|'.join(_COUNT_WORDS)})\s+(?:\w+\s+)?{_COUNTED}", answer, re.I):
        n = _COUNT_WORDS[m.group(1).lower()]
        if n == 0 and "clear" in facts.words:
            continue
        if not any(abs(n - f) < 1e-9 for f in facts.numbers):
            return f"it states '{m.group()}', which no result reported"
    lowered = answer.lower()
    for claim, support in STATE_CLAIMS.items():
        for m in re.finditer(rf"\b{re.escape(claim)}\b", lowered):
            asserted = claim.startswith("no ") or not _negated(lowered, m.start(), m.end())
            if asserted and not support & facts.words:
                return f"it says '{claim}', which no result reported"
            if not asserted and support & facts.words:
                return f"it denies '{claim}', which the robot reported"
    for m in ARRIVAL.finditer(answer):
        if not _negated(lowered, m.start()) and "arrived" not in facts.words:
            return f"it says '{m.group()}', but no arrival was reported"
    for m in OBSTACLE_KINDS.finditer(answer):
        kind = m.group().lower().rstrip("s")
        if kind not in facts.kinds and not _negated(lowered, m.start()):
            return f"it mentions a {kind}, which no result reported"
    return None


def _reported_as(value: float, unit: str, facts: Facts) -> bool:
    """A figure with its unit, as the results gave it (a coordinate without a unit is metres)."""
    for v, u in facts.quantities:
        same = u == unit or (not u and unit == "m")
        if same and abs(v - value) <= 10.0 ** -decimals(f"{value:g}") + 1e-9:
            return True
    return False


def missing(answer: str, executions: list[Execution]) -> str | None:
    """The first fact a read command reported that the answer leaves out; None if none."""
    numbers = [float(n) for n in NUMBER.findall(answer)]
    text = answer.lower()

    def said(value: float, tol: float) -> bool:
        return any(abs(n - value) <= tol for n in numbers)

    for ex in executions:
        v = ex.values
        if not ex.executed or ex.error or not isinstance(v, dict):
            continue
        if stale_age(ex) is not None and not re.search(r"\bago\b|\bold\b", text):
            return "it leaves out how old the robot's reading is"
        role, gap = role_of(ex), None
        if role == "pose" and (pose := pose_of(v)) is not None:
            gap = None if said(pose[0], 0.1) and said(pose[1], 0.1) else "position (x, y)"
        elif role == "battery" and "percentage" in v:
            p = battery_percent(ex)
            gap = None if said(p, 1.0) or said(p / 100, 0.01) else "battery percentage"
        elif role == "obstacles" and "count" in v:
            n = v["count"]
            words = [w for w, k in _COUNT_WORDS.items() if k == n]
            ok = said(n, 0) or any(re.search(rf"\b{w}\b", text) for w in words)
            ok = ok or (n == 0 and bool(re.search(r"\b(?:clear|nothing|none)\b", text)))
            gap = None if ok else "obstacle count"
        elif role == "status" and "state" in v:
            state = str(v["state"])
            ok = state in text or state.replace("_", " ") in text
            gap = None if ok or (state == "e_stopped" and "e-stop" in text) else "state"
        elif role == "conveyor" and "loaded" in v:
            words = ["loaded"] if v["loaded"] else ["empty", "not loaded", "unloaded", "no load"]
            gap = None if any(w in text for w in words) else "load state"
        elif role == "odometry" and "twist" in v:
            t = v["twist"]["twist"]["linear"]
            gap = None if said(math.hypot(t["x"], t["y"]), 0.05) else "speed"
        elif role == "diagnostics" and "status" in v:
            healthy = all(st.get("level", 0) == 0 for st in v["status"])
            pattern = (
                r"\b(?:ok|healthy|normal|no faults?|nominal)\b" if healthy else r"fault|error|warn"
            )
            gap = None if re.search(pattern, text) else "health"
        if gap:
            return f"it leaves out the {gap} the robot reported"
    return None


def factual_answer(
    executions: list[Execution], started: str = "", waited: Iterable[str] = ()
) -> str:
    """The results in words: the same facts the summaries compute, nothing else."""
    if not executions:
        return "No robot command was run."
    lines = [summarize(ex).split("\n", 1)[-1].strip() for ex in executions]
    lines += [w.split(": ", 1)[-1] for w in waited]
    if started:
        lines.append(started)
    return " | ".join(lines)


def nothing_ran(executions: list[Execution]) -> str | None:
    """When no command ran, or every one that ran failed: what was not done and why, in one or
    two plain sentences (the model is not asked to tell a story about it); None otherwise."""
    if any(ex.executed and not ex.error for ex in executions):
        return None
    if not executions:
        return "No robot command was planned for this request, so nothing was sent to the robot."
    sentences = []
    for ex in executions:
        what = _command_words(ex.command)
        if ex.executed:
            sentences.append(f"{what} failed: {_clause(ex.error)}.")
        else:
            sentences.append(f"{what} was not run: {_clause(ex.reason)}.")
    if not any(ex.executed for ex in executions):
        sentences.append("Nothing was sent to the robot.")
    return " ".join(dict.fromkeys(sentences))


def _command_words(command: str) -> str:
    parts = command.split()
    return f"`{' '.join(parts[:4])}`" if len(parts) > 4 else f"`{command}`"


def _clause(text: str) -> str:
    return (text or "no reason was given").strip().rstrip(".")


def sentences(answer: str) -> list[str]:
    """The answer's sentences, split after . ! ? (a decimal point has no space after it)."""
    return [s.strip() for s in _SENTENCE_END.split(answer.strip()) if s.strip()]


def unnamed(sentence: str, facts: Facts) -> str | None:
    """A name in the sentence that nothing in this turn's results or commands mentions, or a
    goal when none of them speaks of one ("its goal was stopped" after a bare /stop)."""
    for m in _NAMED.finditer(sentence):
        name = m.group().lower()
        spaced = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", " ", m.group()).lower()
        if name not in facts.text and spaced not in facts.text:
            return f"it names '{m.group()}', which no result mentions"
    if (m := GOAL.search(sentence)) and not facts.goal_said:
        return f"it speaks of a {m.group().lower()}, which no result mentions"
    return None


def checked_facts(sentence: str, facts: Facts) -> int:
    """How many facts the results hold the sentence states (the request's own numbers and
    words do not count)."""
    n = 0
    for m in NUMBER.finditer(sentence):
        tol = 10.0 ** -decimals(m.group()) + 1e-9
        n += any(abs(float(m.group()) - f) <= tol for f in facts.measured)
    lowered = sentence.lower()
    for m in re.finditer(rf"\b({'|'.join(_COUNT_WORDS)})\s+(?:\w+\s+)?{_COUNTED}", lowered):
        value = _COUNT_WORDS[m.group(1)]
        n += any(abs(value - f) < 1e-9 for f in facts.measured) or (
            value == 0 and "clear" in facts.words
        )
    for claim, support in STATE_CLAIMS.items():
        if re.search(rf"\b{re.escape(claim)}\b", lowered) and support & facts.words:
            n += 1
    n += bool(ARRIVAL.search(sentence)) and "arrived" in facts.words
    n += sum(
        1 for m in OBSTACLE_KINDS.finditer(sentence) if m.group().lower().rstrip("s") in facts.kinds
    )
    for place in facts.places:
        n += place.lower() in lowered or place.replace("_", " ").lower() in lowered
    return n


def grounded(answer: str, facts: Facts, executions: list[Execution]) -> tuple[str, str | None, int]:
    """(what stays, why the answer cannot stand or None, how many sentences or parts were
    dropped). A sentence stays if it states a checked fact and nothing unsupported; in a
    sentence of several parts (split at ";" and ", and"/", but"), each part is held so, and the
    parts that fail are dropped from it."""
    kept, first_reason, dropped = [], None, 0
    for s in sentences(answer):
        parts = _CLAUSE.split(s.rstrip(".!?"))
        ends = s[len(s.rstrip(".!?")) :] or "."
        held = []
        for i in range(0, len(parts), 2):
            text, joint = parts[i], parts[i - 1] if i else ""
            reason = unsupported(text, facts) or unnamed(text, facts)
            if reason is None and checked_facts(text, facts) == 0:
                reason = f"'{text.strip()[:60]}' states no fact the robot reported"
            if reason is None:
                held.append((joint, text))
            else:
                dropped += 1
                first_reason = first_reason or reason
        if held:
            kept.append(_joined(held) + ends)
    text = " ".join(kept)
    if not kept:
        return "", first_reason or "it states nothing the robot reported", dropped
    gap = missing(text, executions)
    return text, gap, dropped


def _joined(held: list[tuple[str, str]]) -> str:
    """The parts that stay, joined as the model joined them; the first one capitalised."""
    text = held[0][1].strip()
    text = text[:1].upper() + text[1:]
    return text + "".join(joint + part for joint, part in held[1:])
