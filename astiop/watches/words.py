"""A watch from the operator's words: "tell me when the battery is below 20 %", "alert me if the
battery drops under 30 percent", "warn me if anything comes within 0.5 m", "let me know when
astibot_2 reaches shipping", "warn me if it is stuck for a minute", "tell me when the conveyor
is loaded". None: the request is no watch (it is planned as before); WatchError: a watch that
cannot be kept (a place or a robot that does not exist), in one line."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence

from astiop.missions.follow import ARRIVED_M
from astiop.watches.model import FIELDS, NO_PROGRESS_S, Watch, WatchError

_ASK = re.compile(
    r"^\s*(?:(?:can|could|would|will)\s+you\s+)?(?:please\s+)?"
    r"(?P<verb>(?:tell|alert|warn|notify|ping)\s+me|let\s+me\s+know)\s*,?\s*"
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
# "when the battery reaches 20 %": which way it is to go is said ("drops to", "charges up to"),
# else read from where the battery is now
_REACH = re.compile(
    r"\b(?:the\s+)?(?:robot'?s\s+)?battery(?:\s+(?:level|charge))?\s+(?:(?P<down>"
    r"(?:drops|falls|goes\s+down|gets\s+down|runs\s+down|is\s+down)\s+to)|(?P<up>"
    r"(?:charges|is\s+charged|climbs|rises|goes\s+up|gets\s+up|is\s+back\s+up|comes\s+back"
    r"(?:\s+up)?)\s+to|is\s+(?:fully\s+)?charged\s+to)|(?:reaches|hits|gets\s+to|is\s+at))"
    rf"\s+{_NUM}",
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
    r"\bfor\s+(?P<n>\d+(?:\.\d+)?|an?|one|two|three|five|ten|half\s+a)\s*"
    r"(?P<u>s|secs?|seconds?|min|mins|minutes?)\b",
    re.I,
)
_COUNTS = {"a": 1.0, "an": 1.0, "one": 1.0, "two": 2.0, "three": 3.0, "five": 5.0, "ten": 10.0}
_WHO = r"(?P<who>the\s+robot|the\s+astibot|it|[a-z][\w-]*(?:\s+\d+)?)"
_PLACE = re.compile(
    rf"^{_WHO}\s+(?:(?P<arrive>reaches|arrives\s+(?:at|in)|gets\s+(?:back\s+)?to|"
    r"makes\s+it\s+to|is\s+back\s+(?:at|to)|has\s+reached|has\s+arrived\s+at)|"
    r"(?P<is>is\s+(?:at|in)))\s+(?:the\s+)?(?P<place>[\w\s-]+?)$",
    re.I,
)
_STUCK = re.compile(
    rf"^{_WHO}\s+(?:"
    r"(?:has\s+not|hasn't|does\s+not|doesn't|did\s+not|didn't)\s+(?:moved?|budged?|"
    r"progressed|made\s+(?:any\s+)?progress)|(?:is|gets|seems|has\s+been|got)\s+stuck|"
    r"stalls|makes\s+no\s+progress|stops\s+making\s+progress)\b",
    re.I,
)
_CONVEYOR = re.compile(
    r"^(?:the\s+(?:robot'?s\s+)?)?(?:conveyor|belt|payload)(?:\s+belt)?\s+"
    r"(?:is|gets|has\s+been|becomes)\s+(?P<how>loaded|full|unloaded|empty|emptied|clear)$"
    r"|^(?:the\s+robot|it)\s+(?:is|gets|has\s+been)\s+(?P<how2>loaded|unloaded)$",
    re.I,
)
# "..., then send it to the dock": the words of a reaction that moves the robot, after the
# condition's; approved by the operator when the watch is made (`split_reaction`)
_THEN = re.compile(
    r"\s*[,;]?\s*(?:and\s+)?\bthen\s+(?=[a-z])"
    r"|\s*[,;]\s*(?:and\s+)?(?=(?:send|drive|move|take|bring|return)\s+(?:it|the\s+robot)\b)",
    re.I,
)
_ROBOT_WORDS = {"the robot", "the astibot", "it"}

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
    n = m["n"].lower()
    count = 0.5 if n.startswith("half") else _COUNTS.get(n) or float(n)
    return count * (60.0 if m["u"].lower().startswith("min") else 1.0)


def _robot_named(who: str, robot: str, robots: Sequence[str]) -> str:
    """The robot a watch's subject names: the one asked (`robot`) for "the robot" or "it", a
    robot of `robots` by its name ("astibot_2", "astibot 2"); WatchError for another name."""
    said = re.sub(r"\s+", " ", who.strip()).lower()
    if said in _ROBOT_WORDS:
        return robot
    key = re.sub(r"[\s_-]+", "", said)
    for name in robots:
        if re.sub(r"[\s_-]+", "", name.lower()) == key:
            return name
    known = f"the robots here: {', '.join(robots)}" if robots else "this console has one robot"
    raise WatchError(f"no robot named '{who.strip()}' ({known})")


def _names_a_robot(who: str, robots: Sequence[str]) -> bool:
    try:
        _robot_named(who, "", robots)
    except WatchError:
        return False
    return True


def _subject(rest: str) -> tuple[str, str]:
    """The words before the condition's verb, and the condition (for a robot named first)."""
    m = re.match(r"^(?P<who>[a-z][\w-]*(?:\s+\d+)?)'s\s+(?P<rest>.+)$", rest, re.I)
    return (m["who"], m["rest"]) if m else ("", rest)


def _place(
    name: str,
    places: Mapping[str, tuple[float, float]],
    resolve: Callable[[str], str | None] | None,
) -> str:
    """The named place the words mean (`resolve`: the agent's reading of a place's name),
    else the one place a word of the name is part of ("the dock": charging_dock)."""
    said = re.sub(r"\s+", " ", name.strip())
    found = resolve(said) if resolve is not None else None
    if found is None:
        exact = [p for p in places if p.lower() == said.lower().replace(" ", "_")]
        word = [p for p in places if said.lower() in p.lower().split("_")]
        found = (exact or word)[0] if len(exact or word) == 1 else None
    if found is None or found not in places:
        known = ", ".join(sorted(places)) or "none on this map"
        raise WatchError(f"there is no place called '{said}' (the places: {known})")
    return found


def _kinds(
    rest: str,
    verb: str,
    when: str,
    robot: str,
    places: Mapping[str, tuple[float, float]],
    resolve: Callable[[str], str | None] | None,
    robots: Sequence[str],
) -> Watch | None:
    """A place, no-progress or conveyor watch (not yet its repeat nor its words), or None."""
    asked = verb.lower().startswith("tell") and when == "if"  # "tell me if it is at X": a question
    body = re.sub(r"\s+(?:during|while\s+on|on)\s+(?:a|its|the)\s+goal$", "", rest, flags=re.I)
    body = _FOR.sub("", body).strip(" ,")
    if m := _PLACE.match(body):
        if m["is"] and asked:
            return None
        try:
            place = _place(m["place"], places, resolve)
        except WatchError:
            if not _names_a_robot(m["who"], robots):
                return None  # neither a robot nor a place ("when battery reaches 20"): no watch
            raise
        who = _robot_named(m["who"], robot, robots)
        x, y = places[place]
        return Watch("place", "<=", ARRIVED_M, robot=who, place=place, x=x, y=y)
    if m := _STUCK.match(body):
        who = _robot_named(m["who"], robot, robots)
        held = _seconds(rest) or NO_PROGRESS_S
        return Watch("no_progress", ">=", held, robot=who)
    if m := _CONVEYOR.match(body):
        if asked:
            return None
        how = (m["how"] or m["how2"]).lower()
        loaded = how in ("loaded", "full")
        return Watch("conveyor", ">=" if loaded else "<=", 1.0 if loaded else 0.0, robot=robot)
    return None


def _reach_op(m: re.Match[str], value: float, now: float | None) -> str:
    """ "drops to 20 %": at most; "charges to 80 %": at least; "reaches 20 %": toward it from
    where the battery is now (`now`, %), or WatchError when that is not known."""
    if m["down"] or m["up"]:
        return "<=" if m["down"] else ">="
    if now is None or round(now, 1) == value:
        why = "no reading of it here" if now is None else f"it is at {now:.1f} % now"
        raise WatchError(
            f"whether the battery is to fall or rise to {value:g} % is not known ({why}): "
            f"say 'below {value:g} %' or 'above {value:g} %'"
        )
    return "<=" if now > value else ">="


def asks_to_be_told(request: str) -> bool:
    """Whether the request asks to be told of something ("tell me when ...", "alert me if ..."):
    only such a request can be a watch."""
    return _ASK.match(request) is not None


def split_reaction(request: str) -> tuple[str, str]:
    """The watch's words and its reaction's: "tell me when the battery is below 20 %, then send
    it to the dock" -> ("tell me when the battery is below 20 %", "send it to the dock");
    ("...", "") when the request names no reaction."""
    m = _THEN.search(request)
    if m is None or _ASK.match(request) is None:
        return request, ""
    return request[: m.start()], request[m.end() :].strip(" .!?")


def watch_from_words(
    request: str,
    robot: str = "",
    places: Mapping[str, tuple[float, float]] | None = None,
    resolve: Callable[[str], str | None] | None = None,
    robots: Sequence[str] = (),
    battery_now: float | None = None,
) -> Watch | None:
    """`robot`: the robot asked; `places`: the named places of its map (x, y); `resolve`: how a
    place's spoken name is read; `robots`: the robots a request may name; `battery_now`: its
    battery (%) as last read, the way "reaches 20 %" goes."""
    ask = _ASK.match(request)
    if ask is None:
        return None
    rest, when = ask["rest"], ask["when"].lower()
    every = when.startswith(("whenever", "each", "every")) or bool(
        re.search(r"\b(?:every|each)\s+time\b", rest, re.I)
    )
    rest = re.sub(r"\s*,?\s*(?:every|each)\s+time$", "", rest, flags=re.I)
    if _THEN.search(rest):  # the caller splits it off first (`split_reaction`)
        raise WatchError(
            "a reaction that moves the robot is approved when the watch is made: "
            "astiop watch add '...' --then dock (or a place)"
        )
    who, rest = _subject(rest)
    if who:
        robot = _robot_named(who, robot, robots)
    kind = _kinds(rest, ask["verb"], when, robot, places or {}, resolve, robots)
    if kind is not None:
        duration = 0.0 if kind.field == "no_progress" else _seconds(rest)
        return Watch(
            kind.field, kind.op, kind.threshold, duration, "every" if every else "once",
            kind.robot, said=request.strip()[:300], place=kind.place, x=kind.x, y=kind.y,
        )  # fmt: skip
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
    elif m := _REACH.search(rest):
        value = _value("battery", m["num"], m["unit"])
        found = ("battery", _reach_op(m, value, battery_now), value)
    if found is None:
        return None
    field, op, threshold = found
    return Watch(
        field, op, threshold, _seconds(rest), "every" if every else "once", robot,
        said=request.strip()[:300],
    )  # fmt: skip
