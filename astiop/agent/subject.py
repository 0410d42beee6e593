"""What a question is about, decided before any read is chosen: a field of one of the robot's
roles, a parameter, the graph, the places, the robot's activity, the journal, astiop itself, or
something outside the robot. The subject decides which reads can answer it
(`astiop.agent.subject_answers`); a question about something else is not answered by a reading
of another role.

A request that asks the robot to do something, or a plain reading the intent reader already
maps to a role ("where is the robot?", "battery level?"), has no subject here: the turn plans it
as before.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from astiop.agent.intent import Intent, resolve_place
from astiop.ros2.roles import ROLES

KINDS = (
    "field",  # what: "role.field" (battery.temperature, pose.heading, scan.range_max)
    "parameter",  # what: the words of the parameter asked about ("max linear speed")
    "graph",  # what: nodes | topics | services | actions; count: how many rather than which
    "places",  # what: count | nearest | distance | between | reachable
    "activity",  # what: why_still
    "view",  # what the robot sees: its camera's frame to a model that takes images (`view`)
    "journal",  # hours: how far back
    "capabilities",
    "outside",
    "unknown",  # a question nothing here nor the intent reader understands
)


@dataclass(frozen=True)
class Subject:
    kind: str
    what: str = ""
    place: str | None = None
    other: str | None = None  # places "between": the second place
    count: bool = False
    hours: float = 1.0
    thing: str = ""  # field: what the question named ("motor", "battery")

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"no subject kind '{self.kind}'")


def _rx(pattern: str) -> re.Pattern[str]:
    return re.compile(pattern, re.I)


_OUTSIDE = _rx(
    r"\b(?:weather|rain(?:ing)?|snow(?:ing)?|forecast|jokes?|funny|poems?|songs?|sing|news|"
    r"stocks?|football|soccer|score of|recipes?|cook|meaning of life|capital of|president|"
    r"who won|movies?|films?|story|stories|riddles?|sunny|cloudy|windy|stormy|translate|horoscope|lottery|your favou?rite|how old are you|are you (?:human|"
    r"alive|conscious)|time is it|what day is|today's date|date today|laugh|amuse|entertain|"
    r"cheer me up|bored|umbrella|sunscreen|traffic)\b"
)
_CAPABILITIES = _rx(
    r"\bwhat (?:can|could) (?:you|i|astiop|this console) (?:do|ask|help)|\bwhat are you "
    r"(?:able|capable)|\b(?:you're|you are) (?:able|capable)\b|\bcapable of\b|"
    r"\byour (?:capabilities|abilities|features|skills)\b|\bhow can you help\b|"
    r"\bwhat (?:sorts?|kinds?|types?) of (?:things|questions|stuff|commands|requests)\b|"
    r"\bwhat (?:do|can) you (?:know|understand|support)\b|\bwhat \w+ (?:do|can) you (?:support|"
    r"offer|handle|do)\b|\bwhat (?:questions|commands) can\b|"
    r"^help\b|\bwhat is astiop\b|\bwho are you\b"
)
_JOURNAL = _rx(
    r"\bwhat (?:did|has) (?:the robot|it|you|the astibot)\b.*\b(?:do|done|been (?:up to|doing))"
    r"|\b(?:history|journal|log|logbook|recent(?:ly)?|so far today|earlier|past|last)\b.*"
    r"\b(?:requests?|commands?|events?|activity|actions?|done|did|happen(?:ed)?)\b"
    r"|\bwhat happened\b|\bwhat has happened\b"
    r"|\b(?:get|got|been) up to\b.*\b(?:last|past|today|earlier)\b"
    r"|\b(?:summar(?:ise|ize|y)|recap|rundown)\b.*\b(?:did|done|last|past|today|earlier)\b"
    r"|\b(?:what|anything)\b.*\b(?:been done|was done|happened|did)\b.*\b(?:last|past|today)\b"
)
_VIEW = _rx(
    r"\bwhat(?:'s| is| are)?(?: there)? (?:in front|ahead|before (?:it|the robot))\b|"
    r"\bwhat (?:does|can|do|did) (?:the robot|the camera|it|you|the astibot|its camera) "
    r"(?:see|look at|show)\b|\bwhat(?:'s| is) (?:the robot|it) (?:looking at|seeing|facing)\b|"
    r"\bwhat(?:'s| is) (?:on|in) (?:the |its )?(?:camera|picture|image|view)\b|"
    r"\b(?:describe|look at) (?:the |its |what )?(?:camera|view|scene|image|picture|frame|"
    r"robot sees|it sees)\b|\bwhat (?:is|'s) (?:visible|in view)\b|\blook (?:ahead|around)\b"
)
_CAMERA_FIELD = _rx(r"\b(?:resolution|size|encoding|format|rate|hz|fps|topic|bytes|pixels)\b")
_HOURS = _rx(r"\b(?:last|past)\s+(\d+(?:\.\d+)?|an?|one|two|three|few)?\s*(minute|hour|day)s?\b")
_GRAPH = {
    "nodes": r"nodes?",
    "topics": r"topics?",
    "services": r"services?",
    "actions": r"actions?(?:\s+servers?)?",
}
_GRAPH_ASK = _rx(
    r"\b(?:list|which|what|how many|show|name|count|enumerate|are there|does it (?:have|run|"
    r"publish|offer)|available|running|published|offered)\b"
)
_COUNT = _rx(r"\bhow many\b|\bcount\b|\bnumber of\b")
_WHY_STILL = _rx(
    r"\bwhy\b.*(?:\bnot|n't|\bnever|no longer|stopped|still|idle|stuck|stationary|standing|"
    r"waiting|parked|halted|frozen|sitting)\b|\bwhat(?:'s| is) (?:stopping|keeping|holding)\b"
    r"|\bwhy (?:is|does|did) (?:it|the robot)\b.*\b(?:stop|wait)"
)
_DISTANCE = _rx(
    r"\bfar\b|\bdistance\b|\bhow (?:many|much) (?:metres|meters|m)\b|\bfar from\b|"
    r"\bhow long (?:a|of a|is the) (?:drive|trip|walk|ride|way|journey|route)\b|"
    r"\b(?:gap|separation)\b|\bhow many (?:metres|meters)\b"
)
_NEAREST = _rx(
    r"\b(?:nearest|closest)\b.*\b(?:places?|stations?|locations?|spots?|stops?)\b|"
    r"\b(?:places?|stations?|locations?|spots?)\b.*\b(?:nearest|closest)\b"
)
_PLACE_COUNT = _rx(
    r"\bhow many\b.*\b(?:places|locations|stations|spots|destinations)\b|"
    r"\bnames? of (?:(?:the|all|every|your|its)\s+)*(?:places|locations|stations|spots)\b"
)
_REACHABLE = _rx(
    r"\bcan (?:it|the robot|you|we) (?:reach|get to|make it to|drive to|go to)\b|\breachable\b"
    r"|\bable to reach\b|\bpossible to (?:reach|get to)\b"
)
_TOP_SPEED = _rx(
    r"\btop speed\b|\bmax(?:imum)? (?:linear |forward |driving )?(?:speed|velocity)\b|"
    r"\bspeed limit\b|\bfastest\b|\bfull speed\b|\bflat out\b|"
    r"\bhow (?:fast|quick(?:ly)?) can (?:it|the robot|you) (?:go|drive|move|travel)\b"
)
_TURN_SPEED = _rx(
    r"\bmax(?:imum)? (?:angular|turn(?:ing)?|rotation(?:al)?|yaw) (?:speed|rate|velocity)\b|"
    r"\bhow fast can (?:it|the robot|you) (?:turn|rotate|spin)\b|"
    r"\b(?:angular|turn(?:ing)?|rotation(?:al)?) (?:speed|velocity|rate) limit\b"
)
_PARAMETER = _rx(
    r"\b(?:parameters?|params?|settings?|configured|configuration|tolerance|inflation|"
    r"wheel (?:radius|size|diameter)|capacity_ah)\b"
)

# a role's fields an operator asks about, and the words that name the role itself: each role's
# own (astiop.ros2.roles), the more specific roles' first (by rank), a role's in its order
FIELDS: dict[tuple[str, str], str] = {
    (r.name, field): words for r in sorted(ROLES, key=lambda r: r.rank) for field, words in r.fields
}
_ROLE_WORDS = {r.name: r.named_by for r in ROLES if r.named_by}
_OTHER_THINGS = (
    r"motors?|wheels?|cpu|computer|processor|lidar|laser|camera|ambient|room|air|warehouse|"
    r"floor|gearbox|drive|controller|board"
)


def subjects_of(
    request: str, intents: list[Intent], places: list[str], unknown: bool = True
) -> list[Subject] | None:
    """A subject for each clause of a request that only asks; None when any clause asks the
    robot to act, or is a plain reading of a role the turn plans as before. `unknown`: a
    question nothing understands is a subject of its own (declined); else left to the plan
    (the rules say what they understand)."""
    if not intents or any(i.actuating or i.kind == "none" for i in intents):
        return None
    found = [subject_of(i, places) for i in intents]
    if any(s is None or (s.kind == "unknown" and not unknown) for s in found):
        return None
    return list(dict.fromkeys(s for s in found if s is not None))  # one answer to one subject


def subject_of(intent: Intent, places: list[str]) -> Subject | None:
    text = intent.clause.strip()
    question = intent.kind in ("read", "list", "unknown")
    if not question:
        return None
    if _OUTSIDE.search(text):
        return Subject("outside")
    if _CAPABILITIES.search(text):
        return Subject("capabilities")
    if _JOURNAL.search(text) and not re.search(r"\b(?:now|right now|currently)\b", text, re.I):
        return Subject("journal", hours=_hours(text))
    if found := _graph(text):
        return found
    if _WHY_STILL.search(text):
        return Subject("activity", "why_still")
    if _VIEW.search(text) and not _CAMERA_FIELD.search(text):
        return Subject("view")
    if found := _places(text, places):
        return found
    if _TURN_SPEED.search(text):
        return Subject("parameter", "max angular speed")
    if _TOP_SPEED.search(text):
        return Subject("parameter", "max linear speed")
    if found := _field(text):
        return found
    if _PARAMETER.search(text):
        return Subject("parameter", _param_words(text))
    if (intent.kind == "unknown" or (intent.kind == "read" and not intent.topic)) and (
        _is_question(text)
    ):
        return Subject("unknown")
    return None


def _is_question(text: str) -> bool:
    return text.endswith("?") or bool(
        re.match(r"(?:what|which|who|why|how|when|where|tell me)\b", text, re.I)
    )


def _hours(text: str) -> float:
    m = _HOURS.search(text)
    if not m:
        return 24.0 if re.search(r"\btoday\b", text, re.I) else 1.0
    n = {"a": 1, "an": 1, "one": 1, "two": 2, "three": 3, "few": 3, None: 1}.get(m.group(1))
    number = float(n if n is not None else m.group(1))
    return number * {"minute": 1 / 60, "hour": 1.0, "day": 24.0}[m.group(2).lower()]


_WHO_PUBLISHES = _rx(
    r"\b(?:which|what) nodes? (?:publish(?:es)?|sends?|subscribes? to|reads?|listens? to)\s+"
    r"(?:the\s+|on\s+)?(/?[\w/]+)|\bwho (?:publishes|subscribes to)\s+(?:the\s+)?(/?[\w/]+)"
)


_TOPIC_TYPE = _rx(r"\b(?:type|message type|interface|msg type)\b")
_ROLE_OF_WORD = {
    "scan": "scan", "lidar": "scan", "laser": "scan", "battery": "battery", "pose": "pose",
    "position": "pose", "odometry": "odometry", "odom": "odometry", "velocity": "velocity_command",
    "status": "status", "map": "map", "obstacles": "obstacles", "diagnostics": "diagnostics",
}  # fmt: skip


def _graph(text: str) -> Subject | None:
    if (m := _TOPIC_TYPE.search(text)) and (named := re.search(r"(?<!\w)(/[\w/]+)", text)):
        return Subject("graph", "type", place=named.group(1))
    if m := _WHO_PUBLISHES.search(text):
        sub = bool(re.search(r"subscrib|reads|listens", m.group(0), re.I))
        named = re.search(r"(?<!\w)(/[\w/]+)", text)  # a topic's own name, else its role's word
        topic = (
            named.group(1)
            if named
            else _ROLE_OF_WORD.get((m.group(1) or m.group(2)).lower(), m.group(1) or m.group(2))
        )
        return Subject("graph", "subscribers" if sub else "publishers", place=topic)
    if not _GRAPH_ASK.search(text) and not re.match(r"(?:nodes|topics|services|actions)\b", text):
        return None
    for what, words in _GRAPH.items():
        if re.search(rf"\b(?:ros ?2? )?{words}\b", text, re.I):
            if what == "actions" and not re.search(r"\baction", text, re.I):
                continue
            return Subject("graph", what, count=bool(_COUNT.search(text)))
    return None


def _places(text: str, places: list[str]) -> Subject | None:
    if _PLACE_COUNT.search(text):
        return Subject("places", "count")
    if _NEAREST.search(text):
        return Subject("places", "nearest")
    named = _named_places(text, places)
    if _DISTANCE.search(text) and named:
        if len(named) >= 2:
            return Subject("places", "between", named[0], named[1])
        return Subject("places", "distance", named[0])
    other_thing = re.search(r"\b(?:obstacle|wall|object|person|thing)", text, re.I) or re.search(
        rf"\b(?:{_ROLE_WORDS['scan']})", text, re.I
    )  # "up to what distance can the lidar see": the lidar's range, not a place's
    if _DISTANCE.search(text) and re.search(r"\b(?:from|to)\s+\w", text, re.I) and not other_thing:
        return Subject("places", "distance", None)  # a place the robot does not know
    if _REACHABLE.search(text):
        return Subject("places", "reachable", named[0] if named else None)
    return None


def _named_places(text: str, places: list[str]) -> list[str]:
    """The named places a question mentions, in the order it names them."""
    m = (
        re.search(r"\bbetween\b(.+?)\band\b(.+)", text, re.I)
        or re.search(r"\bfrom\b(.+?)\bto\b(.+)", text, re.I)
        or re.search(r"(.+)\band\b(.+)", text, re.I)  # "how far apart are A and B"
    )
    if m:
        a, b = resolve_place(m.group(1), places), resolve_place(m.group(2), places)
        if a and b and a != b:
            return [a, b]
    one = resolve_place(text, places)
    return [one] if one else []


def _field(text: str) -> Subject | None:
    """The role's fields a question names ("the battery's temperature and voltage")."""
    found = _one_field(text)
    if found is None or found.thing != found.what.split(".")[0] or "time_to" in found.what:
        return found
    role = found.thing
    names = [f for (r, f), words in FIELDS.items() if r == role and not f.startswith("time_to")
             and re.search(rf"\b(?:{words})", text, re.I)]  # fmt: skip
    if role == "battery" and "charge_ah" in names and "capacity" in names:
        names.remove("capacity")  # "charge in amp hours" is not the capacity
    return Subject("field", f"{role}.{','.join(names)}", thing=role) if names else found


def _one_field(text: str) -> Subject | None:
    for (role, field), words in FIELDS.items():
        if not re.search(rf"\b(?:{words})", text, re.I):
            continue
        words_of_role = _ROLE_WORDS.get(role, "(?!)")  # never, for a role always asked of
        named_role = re.search(rf"\b(?:{words_of_role})", text, re.I)
        other = re.findall(rf"\b({_OTHER_THINGS})\b", text, re.I)  # "wheel motors": motor
        if (
            field in ("temperature", "current", "voltage")
            and other
            and not re.search(r"\bbatter", text, re.I)
        ):
            return Subject("field", f"{role}.{field}", thing=other[-1].lower().rstrip("s"))
        if (
            role in ("pose", "status", "odometry")
            or named_role
            or (role == "battery" and field.startswith("time_to"))
        ):
            return Subject("field", f"{role}.{field}", thing=role)
        if role == "battery" and field in ("voltage", "current", "temperature"):
            return Subject("field", f"{role}.{field}", thing=role)  # the robot's own supply
    return None


def _param_words(text: str) -> str:
    words = re.findall(r"[a-z_]+", text.lower())
    stop = {
        "what", "whats", "is", "the", "robot", "robots", "s", "its", "it", "of", "a", "value",
        "parameter", "parameters", "param", "params", "setting", "settings", "set", "to",
        "configured", "configuration", "current", "currently", "tell", "me", "show", "how",
        "does", "do", "which", "are", "for", "on", "in", "this", "your", "you", "use", "have",
        "has", "any", "all", "list", "give", "there", "names", "every", "each",
    }  # fmt: skip
    return " ".join(w for w in words if w not in stop)
