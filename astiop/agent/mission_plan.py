"""A request of several steps read as a mission, without a model where the words are plain:
"go to shipping, then inspection zone a, then dock", "patrol between the assembly station and
shipping twice", "if the battery is under 30 %, dock first, then go to cps storage", "patrol
between shipping and the assembly station until I stop it" (`until_stopped`).

A model's plan of several goals becomes a mission too, held to the request: only the steps the
request names, in its order (`from_actions`)."""

from __future__ import annotations

import re

from astiop.agent import intent
from astiop.agent.gate import Action, _permits
from astiop.agent.intent import Intent
from astiop.missions.steps import READS, Condition, Step

_COUNTS = {"once": 1, "twice": 2, "thrice": 3, "two": 2, "three": 3, "four": 4, "five": 5}
_TIMES = re.compile(
    r",?\s*\b(?:(once|twice|thrice)|(\d+|two|three|four|five)\s+times)\b(?:\s+over)?", re.I
)
_PATROL = re.compile(r"\bpatrol\b.*?\bbetween\s+(.+?)\s+and\s+(.+)$", re.I)
_WAIT = re.compile(
    r"^(?:then\s+)?(?:wait|pause|stay|hold|sit)\b(?:\s+(?:there|here))?\s+(?:for\s+)?"
    r"(\d+(?:\.\d+)?)\s*(s|sec|secs|seconds?|min|mins|minutes?)\b",
    re.I,
)
_BATTERY_IF = re.compile(
    r"^(?:only\s+)?(?:if|when)\s+(?:the\s+)?(?:battery|charge)(?:\s+level)?\s+(?:is\s+)?"
    r"(under|below|less than|lower than|over|above|more than|higher than)\s+"
    r"(\d+(?:\.\d+)?)\s*(?:%|percent)?\s*,?\s*(.*)$",
    re.I,
)
_OBSTACLE_IF = re.compile(
    r"^(?:only\s+)?(?:if|when)\s+(?:there\s+(?:is|are)\s+(no\s+)?(?:an?\s+|any\s+)?obstacles?"
    r"|(?:the\s+)?(?:way|path)\s+is\s+(clear|blocked))(?:\s+(?:around|nearby|in the way|"
    r"seen))?\s*,?\s*(.*)$",
    re.I,
)
_FIRST = re.compile(r"\s+(?:first|now|next|afterwards|at the end|again)\b", re.I)
_UNKNOWN_PLACE = re.compile(r"\b(?:to|at|visit)\s+(?:the\s+)?([a-z][a-z0-9 _-]{1,40})$", re.I)
_READ_WHAT = {topic: what for what, topic in READS.items()}  # a read step's: battery, obstacles
STEP_CAP = 40  # the most steps a mission holds; a request of more is refused, saying so
COUNT_DIGITS = 12  # a repeat count longer than this is not read (int() of 10**5 digits is slow)


class TooManySteps(Exception):
    """A request that would make a mission of more than STEP_CAP steps; counted, never built."""

    def __init__(self, count: int | None):
        self.count = count  # None: a repeat count of more than COUNT_DIGITS digits
        has = f"{count} steps" if count is not None else "more steps than can be counted"
        super().__init__(
            f"this request has {has}; a mission holds at most {STEP_CAP}: nothing was sent "
            "(split it, or repeat it until stopped)"
        )


_UNTIL_STOPPED = re.compile(
    r",?\s*\b(?:until\s+(?:i|you|we|someone)\s+(?:stop|cancel|halt)(?:\s+(?:it|you|them|this|that))?"
    r"|until\s+(?:i\s+)?(?:tell|told|ask|asked)\s+(?:you\s+|it\s+)?to\s+stop"
    r"|until\s+(?:stopped|canceled|cancelled)|forever|continuously|indefinitely|endlessly"
    r"|non-?stop)\b",
    re.I,
)


def until_stopped(request: str) -> tuple[str, bool]:
    """ "patrol between A and B until I stop it": (the request without the repeat, True). A
    mission repeated so runs round after round until it is canceled."""
    m = _UNTIL_STOPPED.search(request)
    if m is None:
        return request, False
    return (request[: m.start()] + request[m.end() :]).strip(" ,."), True


_MAYBE = re.compile(
    r"\b(?:then|after that|and|patrol|twice|thrice|times|if|when|wait|pause)\b|,", re.I
)


def may_be_mission(request: str, intents: list[Intent]) -> bool:
    """Cheap first look, so a plain one-clause request is classified once per turn."""
    return (
        sum(i.actuating for i in intents) >= 2
        or bool(_MAYBE.search(request))
        and any(i.actuating for i in intents)
    )


def steps_for(request: str, places: dict[str, tuple[float, float]]) -> list[Step] | None:
    """The request's steps when it is a mission (two or more steps, at least one that moves,
    or a condition or a repeat); None when it is not one, or a clause is not plain."""
    names = list(places)
    steps: list[Step] = []
    count = 0  # the steps asked; built only while at most STEP_CAP (a repeat of 10**8 is not)
    shaped = False  # a condition or a repeat makes even one step a mission
    pending_if = ""  # "if the battery is under 30 %," said before the step it holds
    for clause in _pieces(request):
        cond = _BATTERY_IF.match(clause) or _OBSTACLE_IF.match(clause)
        if cond and not cond.group(cond.re.groups).strip(" ,."):
            pending_if = clause.rstrip(" ,.") + ", "
            continue
        clause, pending_if = pending_if + clause, ""
        found = _clause_steps(clause, names, count > 0)
        if found is None:
            return None
        unit, times, special = found
        count = count * times if unit is None else count + len(unit) * times
        if count <= STEP_CAP:
            steps = steps * times if unit is None else steps + unit * times
        shaped = shaped or special
    if count > STEP_CAP:
        raise TooManySteps(count)
    if not steps or not any(s.moves for s in steps):
        return None
    # one goal and a service after it ("go to shipping and unload there") stays a plain turn,
    # which waits for the goal before the service
    return steps if sum(s.moves for s in steps) >= 2 or shaped else None


_VERB_AFTER_COMMA = re.compile(
    r",\s*(?=(?:and\s+)?(?:go|goes|dock|undock|load|unload|wait|pause|return|drive|send|head|"
    r"come|patrol|check|report|read|navigate|move|visit|proceed|travel|if|when|only if)\b)",
    re.I,
)


def _pieces(request: str) -> list[str]:
    """The intent reader's clauses, split again where a comma starts another verb ("undock, go
    to cps storage")."""
    out = []
    for clause in intent.clauses(request):
        out.extend(p.strip(" ,") for p in _VERB_AFTER_COMMA.split(clause) if p.strip(" ,."))
    return [re.sub(r"^and\s+", "", p, flags=re.I) for p in out]


def _clause_steps(
    clause: str, names: list[str], before: bool
) -> tuple[list[Step] | None, int, bool] | None:
    """The clause's steps, once (None: all the steps before it) and how many times, and whether
    it makes a mission of even one step; None: not a plain clause."""
    text = clause.strip(" ,.")
    times, m = 1, _TIMES.search(text)
    if m:
        word = (m.group(1) or m.group(2)).lower()
        if len(word) > COUNT_DIGITS:
            raise TooManySteps(None)
        times = _COUNTS.get(word) or int(word)
        text = (text[: m.start()] + text[m.end() :]).strip(" ,.")
    if not text or re.fullmatch(
        r"(?:and\s+)?(?:repeat|do)\s+(?:it|that|this|all)(?:\s+over)?", text, re.I
    ):
        if times > 1 and before:  # "…, twice": the whole mission so far, again
            return None, times, True
        return None
    if p := _PATROL.search(text):
        a, b = (intent.resolve_place(p.group(i), names) for i in (1, 2))
        if not a or not b or a == b:
            return None
        return [Step("goto", place=a), Step("goto", place=b)], times, True
    if w := _WAIT.match(text):
        seconds = float(w.group(1)) * (60 if w.group(2).lower().startswith("m") else 1)
        return [Step("wait", seconds=seconds)], times, times > 1
    when = None
    if c := _BATTERY_IF.match(text):
        op = "<" if c.group(1).lower() in ("under", "below", "less than", "lower than") else ">"
        when, text = Condition("battery", op, float(c.group(2))), c.group(3)
    elif c := _OBSTACLE_IF.match(text):
        clear = bool(c.group(1)) or (c.group(2) or "").lower() == "clear"
        when = Condition("obstacles", "<", 1) if clear else Condition("obstacles", ">", 0)
        text = c.group(3)
    text = _FIRST.sub("", text).strip(" ,.")
    if not text:
        return None
    it = intent.classify_clause(text, names)
    if it.kind == "unknown":  # "…, then inspection zone a": a bare place in a sequence
        bare = re.sub(r"^(?:then\s+)?(?:back\s+)?(?:to\s+)?", "", text, flags=re.I)
        it = intent.classify_clause(f"go to {bare}", names)
        if it.kind != "navigate" or not (it.place or it.xy):
            return None
    step = _step_of(it, text)
    if step is None:
        return None
    if when is not None:
        step = Step(**{**step.__dict__, "when": when})
    return [step], times, when is not None or times > 1


def _step_of(it: Intent, text: str) -> Step | None:
    if it.kind in ("dock", "undock", "load", "unload"):
        return Step(it.kind)
    if it.kind == "navigate" and it.xy is not None:
        return Step("goto", xy=it.xy, theta=it.theta)
    if it.kind == "navigate" and it.place:
        return Step("goto", place=it.place)
    if it.kind == "navigate":  # a place the robot does not know: the robot says so
        m = _UNKNOWN_PLACE.search(text)
        if m:
            return Step("goto", place=re.sub(r"[\s-]+", "_", m.group(1).strip().lower()))
        return None
    if it.kind == "read" and it.topic in _READ_WHAT:
        return Step("read", what=_READ_WHAT[it.topic])
    return None


def from_actions(
    request: str, actions: list[Action], places: dict[str, tuple[float, float]]
) -> tuple[list[Step] | None, str | None]:
    """A model's plan of several goals as a mission: (steps, None), or (None, why not). Each
    goal must be one the request names, and they must come in the request's order."""
    asked = [i for i in intent.classify(request, list(places)) if i.actuating]
    steps: list[Step] = []
    at = 0
    for action in actions:
        if not action.actuating:
            continue
        match = next((k for k in range(at, len(asked)) if _permits(asked[k], action, places)), None)
        if match is None:
            return None, f"the plan's {_name(action)} is not the request's next step"
        at = match
        steps.append(_step_of_action(action))
    return steps, None


def _step_of_action(action: Action) -> Step:
    if action.kind == "navigate":
        return Step("goto", place=action.place, xy=None if action.place else action.xy)
    return Step(action.kind)


def _name(action: Action) -> str:
    return f"goal to {action.place or action.xy}" if action.kind == "navigate" else action.kind
