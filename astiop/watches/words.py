"""A watch from the operator's words: "tell me when the battery is below 20 %", "alert me if the
battery drops under 30 percent", "warn me if anything comes within 0.5 m". None: the request is
no watch (it is planned as before); WatchError: a watch that cannot be kept, in one line."""

from __future__ import annotations

import re

from astiop.watches.model import FIELDS, Watch, WatchError

_ASK = re.compile(
    r"^\s*(?:(?:can|could|would|will)\s+you\s+)?(?:please\s+)?"
    r"(?:(?:tell|alert|warn|notify|ping)\s+me|let\s+me\s+know)\s*,?\s*"
    r"(?P<when>when(?:ever)?|if|once|as\s+soon\s+as|each\s+time|every\s+time)\s+(?P<rest>.+?)"
    r"[\s.!?]*$",
    re.I,
)
_NUM = r"(?P<num>-?\d+(?:\.\d+)?)\s*(?P<unit>%|(?!(?:for|and|then|during|every|each|on|in)\b)[a-z/]+(?:\s+(?:per\s+second|cent))?)?"
_BELOW = r"below|under|less\s+than|lower\s+than|beneath|at\s+most"
_ABOVE = r"above|over|more\s+than|higher\s+than|greater\s+than|faster\s+than|at\s+least"
_VERB = r"(?:is\s+|goes\s+|drops\s+|falls\s+|gets\s+|runs\s+|rises\s+|climbs\s+|reaches\s+)?"
_BATTERY = re.compile(
    rf"\b(?:the\s+)?(?:robot'?s\s+)?battery(?:\s+(?:level|charge))?\s+{_VERB}"
    rf"(?P<dir>{_BELOW}|{_ABOVE})\s+{_NUM}",
    re.I,
)
_SPEED = re.compile(
    rf"\b(?:the\s+)?(?:robot'?s\s+)?speed\s+{_VERB}(?P<dir>{_BELOW}|{_ABOVE})\s+{_NUM}"
    rf"|\b(?:the\s+robot|it)\s+(?:moves|goes|drives|is\s+going|is\s+moving)\s+"
    rf"(?P<dir2>faster\s+than|slower\s+than|{_ABOVE}|{_BELOW})\s+{_NUM.replace('num', 'num2').replace('unit', 'unit2')}",
    re.I,
)
_NEAR = re.compile(
    r"\b(?:anything|something|anyone|someone|an?\s+(?:obstacle|object|person|thing))\s+"
    r"(?:comes|gets|is|moves)\s+(?:within|closer\s+than|nearer\s+than)\s+"
    rf"{_NUM}",
    re.I,
)
_FOR = re.compile(
    r"\bfor\s+(?P<n>\d+(?:\.\d+)?)\s*(?P<u>s|secs?|seconds?|min|mins|minutes?)\b", re.I
)

_UNITS = {
    "battery": {"": 1.0, "%": 1.0, "percent": 1.0, "per cent": 1.0, "pc": 1.0},
    "speed": {
        "": 1.0, "m/s": 1.0, "mps": 1.0, "meters per second": 1.0, "metres per second": 1.0,
        "cm/s": 0.01, "km/h": 1 / 3.6, "kph": 1 / 3.6,
    },
    "obstacle_distance": {
        "": 1.0, "m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0,
        "cm": 0.01, "centimeters": 0.01, "centimetres": 0.01, "mm": 0.001,
    },
}  # fmt: skip


def _value(field: str, num: str, unit: str | None) -> float:
    unit = re.sub(r"\s+", " ", (unit or "").strip().lower())
    factor = _UNITS[field].get(unit)
    if factor is None:
        spec = FIELDS[field]
        raise WatchError(f"{spec.words} is measured in {spec.unit}, not '{unit}'")
    return float(num) * factor


def _seconds(rest: str) -> float:
    m = _FOR.search(rest)
    if m is None:
        return 0.0
    return float(m["n"]) * (60.0 if m["u"].lower().startswith("min") else 1.0)


def watch_from_words(request: str, robot: str = "") -> Watch | None:
    ask = _ASK.match(request)
    if ask is None:
        return None
    rest, when = ask["rest"], ask["when"].lower()
    every = when.startswith(("whenever", "each", "every")) or bool(
        re.search(r"\b(?:every|each)\s+time\b", rest, re.I)
    )
    found: tuple[str, str, float] | None = None
    if m := _BATTERY.search(rest):
        below = re.match(_BELOW, m["dir"], re.I) is not None
        found = ("battery", "<" if below else ">", _value("battery", m["num"], m["unit"]))
    elif m := _NEAR.search(rest):
        found = ("obstacle_distance", "<", _value("obstacle_distance", m["num"], m["unit"]))
    elif m := _SPEED.search(rest):
        word = m["dir"] or m["dir2"]
        num, unit = (m["num"], m["unit"]) if m["dir"] else (m["num2"], m["unit2"])
        below = word.lower().startswith("slower") or re.match(_BELOW, word, re.I) is not None
        found = ("speed", "<" if below else ">", _value("speed", num, unit))
    if found is None:
        return None
    field, op, threshold = found
    return Watch(
        field, op, threshold, _seconds(rest), "every" if every else "once", robot,
        said=request.strip()[:300],
    )  # fmt: skip
