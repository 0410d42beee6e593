"""The figures a text states: each number, the unit written after it, and what the words before
it call it (a speed, a charge). Read alike in the robot's results and in an answer."""

from __future__ import annotations

import re
from collections.abc import Iterable

NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?![\w])")
# a number and the unit written after it; the unit's normal form is the group's name
_UNIT = re.compile(
    r"\s*(?:(?P<ms>m/s|m per second|met(?:er|re)s? per second)|(?P<rads>rad/s)|"
    r"(?P<pct>%|percent\b)|(?P<V>V\b|volts?\b)|(?P<A>A\b|amps?\b|amperes?\b)|"
    r"(?P<deg>deg\b|degrees?\b)|(?P<m>m\b|met(?:er|re)s?\b))"
)
_UNIT_NAMES = {"ms": "m/s", "rads": "rad/s", "pct": "%", "V": "V", "A": "A", "deg": "deg", "m": "m"}
# a word that names what a figure is, and the unit such a figure has
QUANTITY_WORDS = {
    "speed": "m/s", "velocity": "m/s", "fast": "m/s", "voltage": "V", "heading": "deg",
    "bearing": "deg", "angle": "deg", "battery": "%", "charge": "%", "charged": "%",
    "percentage": "%",
}  # fmt: skip


def quantities_in(text: str) -> list[tuple[float, str]]:
    """Each number of `text` with the unit written after it ("" when none)."""
    return [(value, unit) for value, unit, _ in figures(text)]


def written_figures(text: str) -> Iterable[tuple[str, str]]:
    """Each number of `text` as written, with the unit written after it ("" when none)."""
    for m in NUMBER.finditer(text):
        yield m.group(), unit_after(text, m.end())


def unit_after(text: str, end: int) -> str:
    unit = _UNIT.match(text, end)
    name = next((k for k, v in unit.groupdict().items() if v), "") if unit else ""
    return _UNIT_NAMES.get(name, "")


def figures(text: str) -> Iterable[tuple[float, str, str]]:
    """(number, unit, what the clause before it calls it: a unit or "")."""
    for m in NUMBER.finditer(text):
        clause = re.split(r"[,;:]|\band\b", text[: m.start()])[-1].lower()
        words = re.findall(r"[a-z]+", clause)[-4:]
        called = next((QUANTITY_WORDS[w] for w in reversed(words) if w in QUANTITY_WORDS), "")
        yield float(m.group()), unit_after(text, m.end()), called


def decimals(text: str) -> int:
    return len(text.split(".", 1)[1]) if "." in text else 0
