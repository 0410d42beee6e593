"""The intent gate: a plan runs only if every command in it does what the request asked.

A question never actuates; a stop request yields only a stop; a request to go to a named place
yields only a goal at that place's pose; every other actuation must be one the request names.
The gate sees every plan, from any model or the rules, before confirmation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from astiop.agent.intent import SERVICE_FOR, Intent
from astiop.robot.safety import POSE_STAMPED, VELOCITY_TYPES
from astiop.ros2.validation import CANCEL_SUFFIX, Checked

PLACE_TOLERANCE_M = 0.3


@dataclass(frozen=True)
class Action:
    """What one checked command would do to the robot."""

    kind: str  # read | list | stop | navigate | dock | undock | load | unload | save | motion
    # | configure | release | invalid
    xy: tuple[float, float] | None = None
    place: str | None = None
    twist: tuple[float, float, float] | None = None

    @property
    def actuating(self) -> bool:
        return self.kind not in ("read", "list", "invalid")


_SERVICE_KINDS = {
    **{service: kind for kind, service in SERVICE_FOR.items()},
    "/save_location": "save",
    "/list_locations": "list",
    "/release": "release",  # no request's intent: only the operator releases a held robot
}


def action_of(checked: Checked) -> Action:
    cmd = checked.command
    if not checked.valid or cmd is None:
        return Action("invalid")
    msg = checked.message or {}
    if cmd.key == ("topic", "pub") and checked.type == POSE_STAMPED:
        p = msg.get("pose", {}).get("position", {})  # a goal on a navigator's /goal_pose
        return Action("navigate", xy=(float(p.get("x", 0.0)), float(p.get("y", 0.0))))
    if cmd.key == ("topic", "pub") and checked.type not in VELOCITY_TYPES:
        return Action("configure")  # e.g. amcl's /initialpose: never taken for a stop
    if cmd.key == ("topic", "pub"):
        twist = msg.get("twist", msg)
        lin, ang = twist.get("linear", {}), twist.get("angular", {})
        v = (float(lin.get("x", 0.0)), float(lin.get("y", 0.0)), float(ang.get("z", 0.0)))
        return Action("stop" if not any(v) else "motion", twist=v)
    if cmd.key == ("service", "call"):
        name = checked.local_name or ""
        if name == "/goto_position":
            if msg.get("name"):
                return Action("navigate", place=str(msg["name"]))
            return Action("navigate", xy=(float(msg.get("x", 0.0)), float(msg.get("y", 0.0))))
        if name == "/save_location":
            return Action("save", place=str(msg.get("name", "")))
        kind = _SERVICE_KINDS.get(name)
        if name.endswith(CANCEL_SUFFIX):
            kind = "stop"  # a Nav2 robot's goals cancelled: how it stops without a stop service
        if kind:
            return Action(kind)
        return Action("read" if checked.kind == "read" else "configure")
    if cmd.key == ("action", "send_goal"):
        p = msg.get("pose", {}).get("pose", {}).get("position", {})
        return Action("navigate", xy=(float(p.get("x", 0.0)), float(p.get("y", 0.0))))
    if cmd.key == ("param", "set"):
        return Action("configure", place=str(cmd.args.get("param", "")))
    if checked.kind == "actuate":
        return Action("configure")
    return Action("read")


def _sign_matches(asked: float, sent: float) -> bool:
    return (asked > 0 and sent > 0) or (asked < 0 and sent < 0) or (asked == 0 and sent == 0)


def _permits(intent: Intent, action: Action, places: dict[str, tuple[float, float]]) -> bool:
    if action.kind == intent.kind == "navigate":
        if intent.xy is not None:
            want = intent.xy
        elif intent.place is not None:
            if action.place is not None:
                return action.place.lower() == intent.place.lower()
            want = places.get(intent.place)
            if want is None:
                return False
        else:
            return False  # the request named no place the robot knows
        got = places.get(action.place) if action.place is not None else action.xy
        return got is not None and math.dist(got, want) <= PLACE_TOLERANCE_M
    if action.kind == intent.kind == "motion":
        m = intent.motion
        if m is None or action.twist is None:
            return False
        vx, vy, wz = action.twist
        return _sign_matches(m.vx, vx) and _sign_matches(m.vy, vy) and _sign_matches(m.wz, wz)
    if action.kind == intent.kind == "configure":
        return action.place in (None, intent.place)
    if action.kind == intent.kind == "save":
        return intent.place is None or (action.place or "").lower() == intent.place.lower()
    return action.kind == intent.kind


def check(
    intents: list[Intent], actions: list[tuple[str, Action]], places: dict[str, tuple[float, float]]
) -> str | None:
    """None when the plan does what was asked; else the reason it is refused."""
    asked = [i for i in intents if i.actuating]
    only_stop = bool(intents) and all(i.kind == "stop" for i in intents)
    for text, action in actions:
        if action.kind == "invalid":
            continue  # validation refuses it with its own reason
        if not action.actuating:
            if only_stop:
                return f"the request asks only to stop; `{text}` is not a stop"
            continue
        if any(_permits(i, action, places) for i in asked):
            continue
        return f"`{text}` {_why(action, intents, asked)}"
    return None


def _why(action: Action, intents: list[Intent], asked: list[Intent]) -> str:
    if not asked:
        if any(i.kind == "none" for i in intents):
            return "acts, but the request says not to"
        if intents and all(i.kind in ("read", "list") for i in intents):
            return "would act on the robot, but the request only asks a question"
        return "would act on the robot, but the request does not say what to do (say it plainly)"
    wanted = ", ".join(_describe(i) for i in asked)
    return f"would {_verb(action)}, but the request asks to {wanted}"


def _verb(action: Action) -> str:
    if action.kind == "navigate":
        where = action.place or (f"({action.xy[0]:g}, {action.xy[1]:g})" if action.xy else "?")
        return f"drive to {where}"
    if action.kind == "motion" and action.twist:
        vx, vy, wz = action.twist
        return f"move the robot (vx {vx:g}, vy {vy:g}, wz {wz:g})"
    return {
        "stop": "stop the robot",
        "dock": "dock",
        "undock": "undock",
        "load": "load the conveyor",
        "unload": "unload the conveyor",
        "save": f"save a location '{action.place}'",
        "configure": "change the robot's configuration",
        "release": "release the robot's latched stop (the operator's to do)",
    }.get(action.kind, action.kind)


def _describe(intent: Intent) -> str:
    if intent.kind == "navigate":
        if intent.xy:
            return f"go to ({intent.xy[0]:g}, {intent.xy[1]:g})"
        return f"go to {intent.place}" if intent.place else "go to a place it does not know"
    if intent.kind == "motion" and intent.motion:
        m = intent.motion
        return f"move (vx {m.vx:g}, vy {m.vy:g}, wz {m.wz:g})"
    if intent.kind == "save":
        return f"save this spot as {intent.place}" if intent.place else "save this spot"
    if intent.kind == "configure":
        return f"set {intent.place}"
    return {"load": "load the conveyor", "unload": "unload the conveyor"}.get(
        intent.kind, intent.kind
    )


def other_robot(checks: list[Checked], catalog) -> str | None:
    """Why a plan may not run: it names another robot of the fleet than the one the request is
    about (a name under another robot's namespace), whatever it would do there."""
    from astiop.ros2.fleet_names import robot_under

    for checked in checks:
        name = checked.command.name if checked.command else None
        if checked.namespace and (ns := robot_under(name, checked.namespace, catalog)):
            own = checked.namespace.strip("/")
            return f"this request is about {own}; {name} is another robot's ({ns.strip('/')})"
    return None
