"""A watch: a condition on one numeric reading of one robot, for how long, once or every time,
and what to do (notify). What can be watched is `FIELDS`; each names the roles that give it."""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from astiop.transports.state import RobotState

OPS: dict[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}
OP_WORDS = {"<": "below", "<=": "at most", ">": "above", ">=": "at least"}
REPEATS = ("once", "every")
MAX_DURATION_S = 86400.0


class WatchError(ValueError):
    """A watch that cannot be kept, in one line (nothing was stored)."""


def _battery(s: RobotState) -> float | None:
    return None if s.battery is None else s.battery.percentage * 100.0


def _nearest(s: RobotState) -> float | None:
    """The nearest thing the robot sees: its lidar's shortest finite range, else its nearest
    reported obstacle."""
    if s.scan is not None and len(s.scan.ranges):
        finite = s.scan.ranges[s.scan.ranges < math.inf]
        finite = finite[finite > 0]
        if len(finite):
            return float(finite.min())
    if s.obstacles:
        return min(o.distance for o in s.obstacles)
    return None


@dataclass(frozen=True)
class Field:
    name: str
    roles: tuple[str, ...]  # any of them gives the reading; the first is the one named
    unit: str
    words: str  # "the battery"
    read: Callable[[RobotState], float | None]
    low: float  # the thresholds that make sense
    high: float
    margin: float  # how far back over the threshold a reading must go to clear the condition
    digits: int


FIELDS: dict[str, Field] = {
    "battery": Field("battery", ("battery",), "%", "the battery", _battery, 0, 100, 1.0, 2),
    "speed": Field(
        "speed", ("odometry", "status"), "m/s", "the speed", lambda s: s.speed, 0, 10, 0.02, 2
    ),
    "obstacle_distance": Field(
        "obstacle_distance",
        ("scan", "obstacles"),
        "m",
        "the nearest obstacle",
        _nearest,
        0,
        100,
        0.05,
        2,
    ),  # fmt: skip
}


@dataclass(frozen=True)
class Watch:
    field: str
    op: str
    threshold: float  # in the field's unit
    duration_s: float = 0.0
    repeat: str = "once"
    robot: str = ""  # the robot of a fleet ('' the one robot)
    reaction: str = "notify"
    said: str = ""  # the operator's words
    id: int | None = None
    armed: bool = True

    @property
    def spec(self) -> Field:
        return FIELDS[self.field]

    @property
    def role(self) -> str:
        return self.spec.roles[0]

    def reading(self, value: float) -> str:
        return f"{value:.{self.spec.digits}f} {self.spec.unit}"

    def sentence(self) -> str:
        """The watch in one clause: "the battery is below 20 % for 5 s (every time)"."""
        said = f"{self.condition()} ({'every time' if self.repeat == 'every' else 'once'})"
        if self.reaction == "notify":
            return said
        from astiop.watches.reactions import reaction_words

        return f"{said}, {reaction_words(self.reaction)}"

    def condition(self) -> str:
        """ "the battery is below 20 % for 5 s"."""
        s = self.spec
        what = s.words if not self.robot else f"{s.words} of {self.robot}"
        verb = "is within" if self.field == "obstacle_distance" and self.op in "<=" else "is"
        limit = f"{self.threshold:g} {s.unit}"
        cond = (
            f"{what} {verb} {limit}"
            if verb == "is within"
            else f"{what} is {OP_WORDS[self.op]} {limit}"
        )
        held = f" for {self.duration_s:g} s" if self.duration_s else ""
        return f"{cond}{held}"

    def row(self) -> dict[str, Any]:
        return {
            "robot": self.robot, "role": self.role, "field": self.field, "op": self.op,
            "threshold": self.threshold, "unit": self.spec.unit, "duration_s": self.duration_s,
            "repeat": self.repeat, "reaction": self.reaction, "said": self.said,
        }  # fmt: skip

    def as_json(self) -> dict[str, Any]:
        return {"id": self.id, **self.row(), "armed": self.armed, "sentence": self.sentence()}

    @classmethod
    def from_row(cls, row: dict[str, Any]) -> Watch:
        return cls(
            row["field"], row["op"], float(row["threshold"]), float(row["duration_s"]),
            row["repeat"], row["robot"], row["reaction"], row["said"], row["id"],
            bool(row["armed"]),
        )  # fmt: skip


def validate(watch: Watch, profile: Any = None) -> Watch:
    """The watch, or WatchError with the one-line reason; `profile`: the robot's roles (None:
    not checked here, the evaluator says so where the robot lacks them)."""
    spec = FIELDS.get(watch.field)
    if spec is None:
        raise WatchError(f"nothing called '{watch.field}' can be watched: {', '.join(FIELDS)}")
    if watch.op not in OPS:
        raise WatchError(f"the condition must be one of {' '.join(OPS)}, not '{watch.op}'")
    if not math.isfinite(watch.threshold) or not spec.low <= watch.threshold <= spec.high:
        raise WatchError(
            f"{spec.words} is watched between {spec.low:g} and {spec.high:g} {spec.unit}, "
            f"not {watch.threshold:g}"
        )
    if not math.isfinite(watch.duration_s) or not 0 <= watch.duration_s <= MAX_DURATION_S:
        raise WatchError(f"a watch holds for 0 to {MAX_DURATION_S:g} s")
    if watch.repeat not in REPEATS:
        raise WatchError("a watch fires once or every time")
    if watch.reaction != "notify":
        from astiop.watches.reactions import ReactionError, reaction_steps

        try:
            reaction_steps(watch.reaction)
        except ReactionError as exc:
            raise WatchError(str(exc)) from None
        if watch.repeat != "once":
            raise WatchError("a watch that moves the robot fires once (then armed again by hand)")
    if profile is not None and not any(profile.has(r) for r in spec.roles):
        raise WatchError(f"this robot has no {' or '.join(spec.roles)} to read {spec.words} from")
    return watch
