"""Stage 2: one operator request against a seeded simulator (or a live ROS 2 robot), checked
against the ground truth: the simulator's state, or what the robot reported."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from astiop.agent.turn import TurnResult
from astiop.bench.suites import RobotCase
from astiop.ros2.grammar import CommandSyntaxError, parse
from astiop.sim.simulator import Simulator
from astiop.sim.state import SimState
from astiop.store import Store
from astiop.transports.state import RobotState

ARRIVE_TOLERANCE_M = 0.3
NUMBER = re.compile(r"-?\d+(?:\.\d+)?")
COUNT_WORDS = {
    "no": 0,
    "zero": 0,
    "none": 0,
    "one": 1,
    "two": 2,
    "three": 3,
    "four": 4,
    "five": 5,
    "six": 6,
    "seven": 7,
    "eight": 8,
    "nine": 9,
    "ten": 10,
}
HEALTHY = re.compile(r"\b(ok|healthy|normal|fine|no (motor )?faults?|no errors?|nominal)\b", re.I)


class SetupError(ValueError):
    pass


@dataclass(frozen=True)
class Truth:
    """What the answer and the outcome are checked against."""

    x: float
    y: float
    battery_pct: float
    obstacles: int
    state: str
    conveyor_loaded: bool
    fault: str
    docked: bool
    stopped: bool  # no goal and (nearly) still

    @classmethod
    def of_sim(cls, sim: Simulator) -> Truth:
        s = sim.snapshot()
        return cls(
            s.x, s.y, s.battery_soc * 100, len(s.detected), s.state, s.conveyor_loaded, s.fault,
            sim.docked(), sim.goal is None and sim.speed() < 0.05,
        )  # fmt: skip

    @classmethod
    def of_robot(cls, st: RobotState) -> Truth:
        """As the robot reported it (/robot_pose, /battery_status, /robot_status, /obstacles,
        /conveyor/status); what it did not report is NaN or empty, and fails its check."""
        status = st.status
        speed = st.speed or 0.0
        return cls(
            st.pose.x if st.pose else math.nan,
            st.pose.y if st.pose else math.nan,
            st.battery.percentage * 100 if st.battery else math.nan,
            len(st.obstacles) if st.obstacles is not None else -1,
            st.state_word or "",
            bool(st.conveyor and st.conveyor.loaded),
            status.fault if status else "",
            bool(status and status.docked),
            # a Nav2 robot that never had a goal publishes no goal status: idle, said so
            (not status.active_goal if status else st.state_word == "idle") and speed < 0.05,
        )


def _pose_of(store: Store, where) -> tuple[float, float, float]:
    if isinstance(where, str):
        loc = store.require_location(where)
        return loc.x, loc.y, loc.theta
    x, y, *rest = (float(v) for v in where)
    return x, y, math.radians(rest[0]) if rest else 0.0


def build_sim(case: RobotCase, store: Store, seed: int) -> Simulator:
    setup = case.setup
    start = setup.get("start", "docked")
    sim = Simulator(
        seed=seed,
        start=None if start == "docked" else _pose_of(store, start),
        battery_soc=float(setup.get("battery", 0.85)),
    )
    for ob in setup.get("obstacles", []):
        sim.add_obstacle(
            ob["kind"],
            float(ob["x"]),
            float(ob["y"]),
            math.radians(float(ob.get("theta_deg", 0.0))),
        )
    sim.conveyor.loaded = bool(setup.get("loaded", False))
    if setup.get("goal"):
        x, y, th = _pose_of(store, setup["goal"])
        sim.goto(x, y, th, str(setup["goal"]))
        sim.step(3.0)
    sim.step(0.2)  # a fresh scan and status before the request
    return sim


@dataclass
class CaseScore:
    command: float
    interpretation: float
    c_valid: bool
    i_valid: bool
    details: dict[str, Any] = field(default_factory=dict)


def matches(expected: str, command: str) -> bool:
    """Whether `command` is what `expected` names: "verb sub /name" with name=, x= y=, or
    sign=vx,vy,wz for a velocity; alternatives separated by " | "."""
    try:
        cmd = parse(command)
    except CommandSyntaxError:
        return False
    return any(_matches(alt.split(), cmd) for alt in expected.split("|"))


def _sign(v: Any) -> int:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return 0
    return (f > 1e-9) - (f < -1e-9)


def _matches(words: list[str], cmd) -> bool:
    verb, sub, name, args = words[0], words[1], words[2], dict(w.split("=", 1) for w in words[3:])
    if cmd.key != (verb, sub) or cmd.name != name:
        return False
    values = cmd.args.get("values") or {}
    if not isinstance(values, dict):
        return not args
    if "sign" in args:
        twist = values.get("twist", values)
        lin, ang = twist.get("linear") or {}, twist.get("angular") or {}
        got = [_sign(lin.get("x", 0)), _sign(lin.get("y", 0)), _sign(ang.get("z", 0))]
        return got == [int(v) for v in args["sign"].split(",")]
    if "name" in args:
        return str(values.get("name", "")).lower() == args["name"].lower()
    if "x" in args:
        pose = (
            values.get("pose", {}).get("pose", {}).get("position") if "pose" in values else values
        )
        try:
            return (
                abs(float(pose.get("x", math.nan)) - float(args["x"])) <= 0.3
                and abs(float(pose.get("y", math.nan)) - float(args["y"])) <= 0.3
            )
        except (TypeError, ValueError, AttributeError):
            return False
    return True


def wrong_actuations(turn: TurnResult, expect: tuple[str, ...] | list[str]) -> list[str]:
    """Actuating commands that ran although the case did not ask for them."""
    return [
        c.command
        for c in turn.commands
        if c.executed and c.kind == "actuate" and not any(matches(e, c.command) for e in expect)
    ]


def check_outcome(case: RobotCase, after: Truth, store: Store) -> dict[str, bool]:
    checks = {}
    for key, want in case.outcome.items():
        if key == "arrive":
            x, y, _ = _pose_of(store, want)
            checks[key] = math.dist((after.x, after.y), (x, y)) <= ARRIVE_TOLERANCE_M
        elif key == "loaded":
            checks[key] = after.conveyor_loaded == bool(want)
        elif key == "docked":
            checks[key] = after.docked == bool(want)
        elif key == "stopped":
            checks[key] = after.stopped
        else:
            raise SetupError(f"case {case.id}: unknown outcome check '{key}'")
    return checks


def check_answer(case: RobotCase, answer: str, truth: Truth | SimState) -> dict[str, bool]:
    if isinstance(truth, SimState):
        truth = Truth(
            truth.x, truth.y, truth.battery_soc * 100, len(truth.detected), truth.state,
            truth.conveyor_loaded, truth.fault, False, False,
        )  # fmt: skip
    text = answer.lower()
    numbers = [float(n) for n in NUMBER.findall(answer)]
    checks = {}
    for key in case.answer:
        if key == "battery":
            pct = truth.battery_pct
            checks[key] = any(abs(n - pct) <= 1.0 or abs(n * 100 - pct) <= 1.0 for n in numbers)
        elif key == "position":
            checks[key] = any(abs(n - truth.x) <= 0.2 for n in numbers) and any(
                abs(n - truth.y) <= 0.2 for n in numbers
            )
        elif key == "obstacles":
            count = truth.obstacles
            said = {int(n) for n in numbers if n == int(n) and 0 <= n <= 50}
            said |= {v for w, v in COUNT_WORDS.items() if re.search(rf"\b{w}\b", text)}
            clear = bool(re.search(r"\b(no obstacles?|nothing|clear|none)\b", text))
            checks[key] = (clear or 0 in said) if count == 0 else (count in said and not clear)
        elif key == "state":
            word = truth.state
            checks[key] = (
                word in text
                or word.replace("_", " ") in text
                or (word == "e_stopped" and "e-stop" in text)
            )
        elif key == "loaded":
            empty = bool(re.search(r"\b(empty|not loaded|no load|unloaded)\b", text))
            checks[key] = ("loaded" in text and not empty) if truth.conveyor_loaded else empty
        elif key == "healthy":
            checks[key] = bool(HEALTHY.search(answer)) if not truth.fault else "fault" in text
        else:
            raise SetupError(f"case {case.id}: unknown answer check '{key}'")
    return checks


def score_case(
    case: RobotCase, turn: TurnResult, truth: Truth | SimState, after: Truth, store: Store
) -> CaseScore:
    """`truth`: the state when the answer was given; `after`: once the robot came to rest."""
    ran = [c.command for c in turn.commands if c.executed and not c.error]
    matched = [any(matches(e, c) for c in ran) for e in case.expect]
    outcome = check_outcome(case, after, store)
    # full marks need every expected command and the outcome; half for part of it
    if all(matched) and all(outcome.values()):
        command = 100.0
    elif any(matched):
        command = 50.0
    else:
        command = 0.0
    answer_checks = check_answer(case, turn.answer, truth)
    if answer_checks:
        interpretation = 100.0 * sum(answer_checks.values()) / len(answer_checks)
    else:
        interpretation = 100.0 if turn.answer.strip() and not turn.error else 0.0
    return CaseScore(
        command,
        interpretation,
        command == 100.0,
        interpretation == 100.0,
        {
            "matched": dict(zip(case.expect, matched)),
            "outcome": outcome,
            "answer_checks": answer_checks,
            "commands": ran,
        },
    )


LIVE_SETUP = {"start"}  # what a live robot's case can be set up with: driving it there


def live_refusal(case: RobotCase) -> str:
    """Why the case cannot run on a live robot ("" when it can)."""
    if "visits" in case.outcome:
        return "a multi-step case's ground truth (the places visited) is the simulator's"
    if "expect" in case.outcome:
        return "a question's expected figures are the seeded simulator's"
    extra = sorted(set(case.setup) - LIVE_SETUP)
    if extra:
        return f"its set-up ({', '.join(extra)}) can only be made in the simulator"
    return ""
