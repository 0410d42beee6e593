"""A mission's steps: what each one is, the command that starts it, and how it reads."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from typing import Any

from astiop.ros2.render import nav_goal_command
from astiop.ros2.roles import ROLE_BY_NAME

GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition"
TRIGGER = "std_srvs/srv/Trigger"
SERVICES = {
    "dock": "/dock",
    "undock": "/undock",
    "load": "/conveyor/load",
    "unload": "/conveyor/unload",
}
KINDS = frozenset({"goto", "wait", "read", *SERVICES})
# what a step may read, and the topic it reads it from
READS = {what: ROLE_BY_NAME[what].key for what in ("battery", "obstacles")}  # the ASTIbot's
STOP = f"ros2 service call /stop {TRIGGER}"


def read_name(what: str, profile: Any = None) -> str:
    """The topic a read step reads on this robot (its battery role's name on any robot)."""
    if profile is not None and what == "battery":
        return profile.name("battery") or READS[what]
    return READS[what]


@dataclass(frozen=True)
class Condition:
    """A reading the step depends on: run the step only if `what` `op` `value`
    (battery in %, obstacles as a count)."""

    what: str  # battery | obstacles
    op: str  # < | >
    value: float

    def holds(self, reading: float) -> bool:
        return reading < self.value if self.op == "<" else reading > self.value

    def text(self) -> str:
        if self.what == "battery":
            return f"battery {'under' if self.op == '<' else 'over'} {self.value:g} %"
        if self.op == ">" and self.value == 0:
            return "an obstacle is seen"
        if self.op == "<" and self.value == 1:
            return "no obstacle is seen"
        return f"obstacles {self.op} {self.value:g}"


@dataclass(frozen=True)
class Step:
    kind: str  # goto | dock | undock | load | unload | wait | read
    place: str | None = None  # goto: a named place
    xy: tuple[float, float] | None = None  # goto: coordinates
    theta: float | None = None
    seconds: float = 0.0  # wait
    what: str | None = None  # read: battery | obstacles
    when: Condition | None = None  # run only if this holds

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown step kind '{self.kind}'")
        if self.kind == "goto" and not self.place and self.xy is None:
            raise ValueError("a goto step needs a place or x, y")
        if self.kind == "read" and self.what not in READS:
            raise ValueError(f"a read step reads one of {', '.join(READS)}")
        if self.kind == "wait" and not 0 < self.seconds <= 3600:
            raise ValueError("a wait step lasts more than 0 s and at most 3600 s")

    @property
    def moves(self) -> bool:
        return self.kind in ("goto", "dock", "undock")

    def command(self, profile: Any = None, locate: Any = None) -> str | None:
        """The ros2 command that starts the step (None: a wait, or a read's own echo), in the
        names of the robot's `profile` (the ASTIbot's without one): on a Nav2 robot a goto is a
        NavigateToPose goal (a place by its coordinates, `locate(place)`); a dock or undock the
        robot lacks is None."""
        if profile is not None and self.kind in ("dock", "undock"):
            name = profile.name(self.kind)
            return f"ros2 service call {name} {TRIGGER}" if name else None
        action = profile.name("navigation") if profile is not None else None
        if self.kind == "goto" and action and profile.kind("navigation") == "action":
            xy = self.xy or (locate(self.place) if locate and self.place else None)
            return nav_goal_command(action, xy[0], xy[1], self.theta or 0.0) if xy else None
        if self.kind in SERVICES:
            return f"ros2 service call {SERVICES[self.kind]} {TRIGGER}"
        if self.kind == "goto" and self.xy is not None:
            x, y = self.xy
            return f'{GOTO} "{{x: {x:.3f}, y: {y:.3f}, theta: {self.theta or 0.0:.4f}}}"'
        if self.kind == "goto":
            return f"{GOTO} \"{{name: '{self.place}'}}\""
        if self.kind == "read":
            return f"ros2 topic echo {read_name(self.what or '', profile)} --once"
        return None

    def target(self) -> str:
        """The goal's name as the robot reports it (a place, coordinates, dock, undock)."""
        if self.kind == "goto":
            return self.place or f"({self.xy[0]:g}, {self.xy[1]:g})"  # type: ignore[index]
        return self.kind

    def label(self) -> str:
        if self.kind == "goto":
            text = f"go to {self.target()}"
        elif self.kind == "wait":
            text = f"wait {self.seconds:g} s"
        elif self.kind == "read":
            text = f"read the {self.what}"
        else:
            text = self.kind
        return f"if {self.when.text()}: {text}" if self.when else text

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @staticmethod
    def from_json(text: str) -> Step:
        d = json.loads(text)
        when = Condition(**d["when"]) if d.get("when") else None
        xy = tuple(d["xy"]) if d.get("xy") is not None else None
        return Step(**{**d, "when": when, "xy": xy})


def describe(steps: list[Step], forever: bool = False) -> str:
    """'1. go to shipping; 2. dock' — the whole mission on one line (approval, answers); one
    repeated until stopped says so, with no count."""
    text = "; ".join(f"{i}. {s.label()}" for i, s in enumerate(steps, 1))
    return f"{text}; repeated until stopped" if forever else text
