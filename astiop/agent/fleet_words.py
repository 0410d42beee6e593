"""Which robot of a fleet a request is about, read without the model: its name ("astibot 3",
"astibot_3"), its number ("robot 3"), where it is ("the one at shipping"), or a choice ("the
nearest idle robot to the assembly station"); and the questions about the whole fleet ("where
are all the robots?", "which robot has the lowest battery?"), answered from every robot's
reported state, a stale robot said to be stale."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

from astiop.robot.fleet_watch import FleetRow

NUMBERS = {
    "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8,
    "nine": 9, "ten": 10, "first": 1, "second": 2, "third": 3, "fourth": 4, "fifth": 5,
}  # fmt: skip
AT_PLACE_M = 1.5  # "the one at shipping": within this of the place
_NUMBER = r"(?:number\s+|no\.?\s*|#\s*)?(\d+|" + "|".join(NUMBERS) + r")\b"


@dataclass(frozen=True)
class Addressed:
    name: str  # the robot
    request: str  # the request as said to that robot ("send the robot to shipping")
    how: str  # how it was picked, said to the operator ("as named", "the one at shipping")


class FleetWordsError(ValueError):
    """A request that names robots it cannot be run on, in one line."""


def _split(name: str) -> tuple[str, int | None]:
    m = re.fullmatch(r"(.*?)[_-]?(\d+)", name)
    return (m.group(1), int(m.group(2))) if m else (name, None)


def _number(word: str) -> int:
    return int(word) if word.isdigit() else NUMBERS[word.lower()]


def _mentions(request: str, names: Sequence[str]) -> list[tuple[str, re.Match]]:
    """Every robot the request names, with where."""
    found: list[tuple[str, re.Match]] = []
    numbered = {}
    for name in names:
        prefix, n = _split(name)
        if n is not None:
            numbered.setdefault(n, []).append(name)
        spaced = re.escape(name).replace(r"_", r"[\s_-]*").replace(r"\-", r"[\s_-]*")
        pattern = rf"\b{spaced}\b"
        if n is not None and prefix:
            pattern = rf"\b{re.escape(prefix)}[\s_-]*{_NUMBER}"
        for m in re.finditer(pattern, request, re.IGNORECASE):
            if n is None or _number(m.group(1)) == n:
                found.append((name, m))
    if not found:  # "robot 3": the robot numbered 3, when one name has that number
        for m in re.finditer(rf"\brobot\s+{_NUMBER}", request, re.IGNORECASE):
            n = _number(m.group(1))
            if len(numbered.get(n, [])) == 1:
                found.append((numbered[n][0], m))
            elif 1 <= n <= len(names) and not numbered:
                found.append((names[n - 1], m))
    return found


def _place_in(request: str, places: dict[str, tuple[float, float]]) -> str | None:
    low = request.lower()
    for place in sorted(places, key=len, reverse=True):
        if re.search(rf"\b{re.escape(place.lower()).replace('_', '[ _]')}\b", low):
            return place
    return None


def _fresh(rows: Sequence[FleetRow]) -> list[FleetRow]:
    return [r for r in rows if not r.stale and not r.error and r.x is not None]


def _dist(row: FleetRow, xy: tuple[float, float]) -> float:
    return math.hypot(row.x - xy[0], row.y - xy[1])


def addressed(
    request: str,
    rows: Sequence[FleetRow],
    places: dict[str, tuple[float, float]],
) -> Addressed | None:
    """The robot the request is about (None: it names none); FleetWordsError for a request that
    names two robots, or picks one no robot fits."""
    names = [r.name for r in rows]
    found = _mentions(request, names)
    if len({name for name, _ in found}) > 1:
        named = ", ".join(dict.fromkeys(name for name, _ in found))
        raise FleetWordsError(f"one robot per request: this one names {named}")
    if found:
        name, m = found[0]
        said = request[: m.start()] + "the robot" + request[m.end() :]
        said = re.sub(r"\bthe\s+the robot", "the robot", said, flags=re.IGNORECASE)
        return Addressed(name, said, "as named")
    choice = re.search(
        r"\bthe\s+(nearest|closest)\s+(idle\s+|free\s+|available\s+)?robot\b", request, re.I
    )
    if choice:
        place = _place_in(request[choice.end() :], places)
        if place is None:
            raise FleetWordsError("nearest to where? name a place, e.g. 'to shipping'")
        idle = bool(choice.group(2))
        fits = [r for r in _fresh(rows) if not idle or r.state == "idle"]
        if not fits:
            which = "idle robot" if idle else "robot"
            raise FleetWordsError(f"no {which} of the fleet has reported its pose just now")
        best = min(fits, key=lambda r: _dist(r, places[place]))
        said = request[: choice.start()] + "the robot" + request[choice.end() :]
        how = f"the nearest {'idle ' if idle else ''}robot to {place}"
        return Addressed(best.name, said, how + f", {_dist(best, places[place]):.1f} m away")
    at = re.search(r"\bthe\s+(one|robot)\s+(at|near|by)\s+(the\s+)?", request, re.I)
    if at:
        rest = request[at.end() :].lower().replace(" ", "_")
        place = next((p for p in places if rest.startswith(p.lower().replace(" ", "_"))), None)
        if place is not None:
            near = [r for r in _fresh(rows) if _dist(r, places[place]) <= AT_PLACE_M]
            if len(near) != 1:
                n = "no robot is" if not near else f"{len(near)} robots are"
                raise FleetWordsError(f"{n} at {place} now: name the robot")
            end = at.end() + len(place)
            return Addressed(near[0].name, request[: at.start()] + "the robot" + request[end:],
                             f"the one at {place}")  # fmt: skip
    return None


# -- questions about the whole fleet -------------------------------------------------------
_ALL = re.compile(
    r"\b(all|every|each)\s+(the\s+|of\s+the\s+)?robots?\b|\bthe\s+robots\b|\bfleet\b"
    r"|\bwhich\s+robot\b|\bhow\s+many\s+robots\b|\brobots'",
    re.IGNORECASE,
)


def fleet_question(request: str) -> str | None:
    """ "lowest_battery", "highest_battery", "positions", "batteries", "status", or None: not
    a question about the whole fleet."""
    if not _ALL.search(request):
        return None
    low = request.lower()
    if re.search(r"\bwhich\s+robot\b", low) and "battery" in low:
        high = re.search(r"\b(highest|most|fullest|best|largest)\b", low)
        return "highest_battery" if high else "lowest_battery"
    if re.search(r"\bwhich\s+robot\b", low):
        return None  # "which robot is nearest…": a choice, not asked here
    if "where" in low or "position" in low or "pose" in low:
        return "positions"
    if "battery" in low or "batteries" in low or "charge" in low:
        return "batteries"
    return "status"


def _stale(row: FleetRow) -> str:
    if row.error:
        return f"{row.name}: {row.error}"
    if row.age_s is None:
        return f"{row.name}: not heard from yet"
    return f"{row.name}: stale, last heard {row.age_s:.0f} s ago"


def _where(row: FleetRow) -> str:
    if row.x is None:
        return f"{row.name}: no pose reported"
    return f"{row.name} at x {row.x:.2f} m, y {row.y:.2f} m ({row.state})"


def _battery(row: FleetRow) -> str:
    if row.battery is None:
        return f"{row.name}: no battery reading"
    return f"{row.name} {row.battery * 100:.1f} %"


def fleet_answer(kind: str, rows: Sequence[FleetRow]) -> str:
    """The answer to a fleet question from every robot's row: a value only as reported, a
    robot not heard lately said to be stale (its old value is not given as now)."""
    fresh = [r for r in rows if not r.stale and not r.error]
    stale = [_stale(r) for r in rows if r.stale or r.error]
    tail = ("\n" + "\n".join(stale)) if stale else ""
    if not rows:
        return "The fleet has no robots."
    if kind in ("lowest_battery", "highest_battery"):
        read = sorted((r for r in fresh if r.battery is not None), key=lambda r: r.battery)
        if not read:
            return "No robot of the fleet has reported its battery just now." + tail
        best, word = (read[0], "lowest") if kind == "lowest_battery" else (read[-1], "highest")
        others = ", ".join(_battery(r) for r in read)
        head = f"{best.name} has the {word} battery: {best.battery * 100:.1f} %."
        return f"{head} All reported: {others}." + tail
    if kind == "positions":
        lines = [_where(r) for r in fresh]
    elif kind == "batteries":
        lines = [_battery(r) for r in fresh]
    else:
        lines = [f"{_where(r)}, battery {_battery(r).split(' ', 1)[1]}" for r in fresh]
    head = f"{len(rows)} robots, {len(fresh)} reporting now:"
    return "\n".join([head, *lines]) + tail
