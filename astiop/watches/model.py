"""A watch: a condition on one reading of one robot, for how long, once or every time, and what
to do (notify). What can be watched is `FIELDS`, one entry per kind: a numeric threshold (the
battery, the speed, the nearest obstacle), being at a named place, no progress toward a goal,
the conveyor loaded or empty. Each names the roles that give its reading, how it reads it
from a `Sample`, and how its condition is said; every kind is a value compared with the
watch's threshold, so they all share one edge (`builtins.Edge`) and one table row."""

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
NO_PROGRESS_S = 30.0  # a no-progress watch said without its time ("if it gets stuck")


class WatchError(ValueError):
    """A watch that cannot be kept, in one line (nothing was stored)."""


def battery_percent(s: RobotState) -> float | None:
    """The battery's charge in %, None with no reading."""
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
class Sample:
    """What a watch reads: the robot's state, and how long it has made no progress toward the
    goal it runs (None: no goal runs, or the E-STOP holds; `builtins.Progress` keeps it)."""

    state: RobotState
    stalled_s: float | None = None


@dataclass(frozen=True)
class Field:
    name: str
    roles: tuple[str, ...]  # any of them gives the reading; the first is the one named
    unit: str
    words: str  # "the battery"
    read: Callable[[Sample, Watch], float | None]
    low: float  # the thresholds that make sense
    high: float
    margin: float  # how far back over the threshold a reading must go to clear the condition
    digits: int
    said: Callable[[Watch, str], str] | None = None  # the condition (`what`: the robot's words)
    lacking: str = ""  # why a robot without its roles cannot be watched so


def _threshold(s: Callable[[RobotState], float | None]) -> Callable[[Sample, Watch], float | None]:
    return lambda sample, _watch: s(sample.state)


def _to_place(sample: Sample, watch: Watch) -> float | None:
    pose = sample.state.pose
    return None if pose is None else math.dist((pose.x, pose.y), (watch.x, watch.y))


def _loaded(sample: Sample, _watch: Watch) -> float | None:
    conveyor = sample.state.conveyor
    return None if conveyor is None else float(conveyor.loaded)


def _stalled(sample: Sample, _watch: Watch) -> float | None:
    return 0.0 if sample.stalled_s is None else sample.stalled_s  # no goal: cleared


def _at_place(w: Watch, what: str) -> str:
    return f"{what} is at {w.place} (within {w.threshold:g} m)"


def _no_progress(w: Watch, what: str) -> str:
    return f"{what} makes no progress toward its goal for {w.threshold:g} s"


def _conveyor(w: Watch, what: str) -> str:
    return f"{what} is {'loaded' if w.op == '>=' else 'empty'}"


FIELDS: dict[str, Field] = {
    "battery": Field(
        "battery", ("battery",), "%", "the battery", _threshold(battery_percent), 0, 100, 1.0, 2
    ),
    "speed": Field(
        "speed", ("odometry", "status"), "m/s", "the speed", _threshold(lambda s: s.speed),
        0, 10, 0.02, 2,
    ),
    "obstacle_distance": Field(
        "obstacle_distance", ("scan", "obstacles"), "m", "the nearest obstacle",
        _threshold(_nearest), 0, 100, 0.05, 2,
    ),
    # the robot within the arrival tolerance of a named place (its x, y kept with the watch)
    "place": Field(
        "place", ("pose", "odometry"), "m", "the robot", _to_place, 0.05, 10, 0.2, 2, _at_place,
        "this robot reports no pose",
    ),
    # seconds without progress toward the goal that runs, as the built-in alert counts them;
    # cleared by progress (the count starts again) or the goal's end
    "no_progress": Field(
        "no_progress", ("status",), "s", "the robot", _stalled, 1, MAX_DURATION_S, 0.0, 0,
        _no_progress, "this robot reports no goal status",
    ),
    # 1 loaded, 0 empty
    "conveyor": Field(
        "conveyor", ("conveyor",), "", "the conveyor", _loaded, 0, 1, 0.5, 0, _conveyor,
        "this robot reports no conveyor",
    ),
}  # fmt: skip
KIND_OPS = {"place": ("<=",), "no_progress": (">=",), "conveyor": (">=", "<=")}


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
    place: str = ""  # a place watch's place, and its x, y on the robot's map
    x: float = 0.0
    y: float = 0.0

    @property
    def spec(self) -> Field:
        return FIELDS[self.field]

    @property
    def role(self) -> str:
        return self.spec.roles[0]

    def reading(self, value: float) -> str:
        if self.field == "conveyor":
            return "loaded" if value >= 0.5 else "empty"
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
        held = f" for {self.duration_s:g} s" if self.duration_s else ""
        if s.said is not None:  # "the robot" is the robot named, where it is named
            what = s.words
            if self.robot:
                what = self.robot if what == "the robot" else f"{what} of {self.robot}"
            return f"{s.said(self, what)}{held}"
        what = s.words if not self.robot else f"{s.words} of {self.robot}"
        verb = "is within" if self.field == "obstacle_distance" and self.op in "<=" else "is"
        limit = f"{round(self.threshold, 3):g} {s.unit}"  # 1 km/h: 0.278 m/s
        cond = (
            f"{what} {verb} {limit}"
            if verb == "is within"
            else f"{what} is {OP_WORDS[self.op]} {limit}"
        )
        return f"{cond}{held}"

    def row(self) -> dict[str, Any]:
        return {
            "robot": self.robot, "role": self.role, "field": self.field, "op": self.op,
            "threshold": self.threshold, "unit": self.spec.unit, "duration_s": self.duration_s,
            "repeat": self.repeat, "reaction": self.reaction, "said": self.said,
            "place": self.place, "x": self.x, "y": self.y,
        }  # fmt: skip

    def as_json(self) -> dict[str, Any]:
        return {"id": self.id, **self.row(), "armed": self.armed, "sentence": self.sentence()}

    @classmethod
    def from_row(cls, row: dict[str, Any]) -> Watch:
        return cls(
            row["field"], row["op"], float(row["threshold"]), float(row["duration_s"]),
            row["repeat"], row["robot"], row["reaction"], row["said"], row["id"],
            bool(row["armed"]), row.get("place") or "", float(row.get("x") or 0.0),
            float(row.get("y") or 0.0),
        )  # fmt: skip


def validate(watch: Watch, profile: Any = None) -> Watch:
    """The watch, or WatchError with the one-line reason; `profile`: the robot's roles (None:
    not checked here, the evaluator says so where the robot lacks them)."""
    spec = FIELDS.get(watch.field)
    if spec is None:
        raise WatchError(f"nothing called '{watch.field}' can be watched: {', '.join(FIELDS)}")
    ops = KIND_OPS.get(watch.field, tuple(OPS))
    if watch.op not in ops:
        raise WatchError(f"the condition must be one of {' '.join(ops)}, not '{watch.op}'")
    if (watch.field == "place") != bool(watch.place):
        raise WatchError("a place watch names its place, and only a place watch does")
    if not (math.isfinite(watch.x) and math.isfinite(watch.y)):
        raise WatchError("a place's coordinates must be numbers")
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
        raise WatchError(
            spec.lacking or f"this robot has no {' or '.join(spec.roles)} to read {spec.words} from"
        )
    return watch
