"""Answers computed from more than one reading: the robot's pose and the named places' coordinates
(how far, the nearest, between two), and the battery's time to full or to empty from its charge,
capacity and current. Each says how it was worked out."""

from __future__ import annotations

import math
from typing import Any

from astiop.agent.subject import Subject


def answer(subject: Subject, reads: Any, places: dict[str, tuple[float, float]]) -> str:
    what = subject.what
    if not places:
        return "The robot knows no named places (none saved, none on its map)."
    if what == "count":
        names = ", ".join(sorted(places))
        return f"The robot knows {len(places)} named places: {names}."
    if what in ("distance", "reachable") and subject.place is None:
        known = ", ".join(sorted(places))
        return f"That names no place the robot knows; its places are: {known}."
    if what == "between":
        a, b = places[subject.place], places[subject.other]
        d = math.dist(a, b)
        return (
            f"{subject.place} and {subject.other} are {d:.1f} m apart in a straight line "
            f"({_xy(a)} to {_xy(b)}); the path the robot drives around shelves is longer."
        )
    pose = reads.pose()
    if pose is None:
        missing = "publishes no pose" if not reads.gateway.profile.has("pose") else "gave no pose"
        return f"The robot {missing}, so I cannot say how far it is from a place."
    here = pose[:2]
    if what == "nearest":
        ranked = sorted(places, key=lambda n: math.dist(here, places[n]))
        first = ranked[0]
        then = (
            f"; then {ranked[1]} at {math.dist(here, places[ranked[1]]):.1f} m"
            if len(ranked) > 1
            else ""
        )
        return (
            f"The nearest place is {first}, {math.dist(here, places[first]):.1f} m from the "
            f"robot at {_xy(here)} in a straight line{then}."
        )
    d = math.dist(here, places[subject.place])
    line = (
        f"The robot at {_xy(here)} is {d:.1f} m from {subject.place} at "
        f"{_xy(places[subject.place])} in a straight line"
    )
    if what == "reachable":
        return (
            f"{subject.place} is a named place {d:.1f} m away in a straight line; whether a "
            "free path leads there is known only once a goal is sent (nothing was sent)."
        )
    return line + " (the path it would drive is longer where shelves are in the way)."


def _xy(p) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def battery_time(name: str, v: dict, pct: float | None) -> str:
    """Time to full (charging) or to empty (discharging): the charge left to fill or to use,
    in Ah, over the current the battery reports, in A."""

    charge, capacity, current = (battery_figure(v, k) for k in ("charge", "capacity", "current"))
    at = f"at {pct:.1f} %" if pct is not None else "charge unknown"
    if current is None or charge is None or (name == "time_to_full" and not capacity):
        return (
            f"The battery is {at}; it does not report its charge, capacity and current, so "
            "the time cannot be computed."
        )
    charging = current > 0
    if name == "time_to_full" and not charging:
        return f"The battery is {at} and not charging (current {current:.2f} A): it will not fill."
    if name == "time_to_empty" and charging:
        return (
            f"The battery is {at} and charging (current +{current:.2f} A), so it is not running "
            "down now."
        )
    if abs(current) < 1e-3:
        return f"The battery is {at} and no current flows: the time cannot be computed."
    if name == "time_to_full":
        hours = max(0.0, capacity - charge) / current
        how = f"({capacity:.1f} - {charge:.1f} Ah) / {current:.2f} A"
        return f"The battery is {at}; full in about {_hm(hours)}: {how}, at the present current."
    hours = charge / abs(current)
    how = f"{charge:.1f} Ah / {abs(current):.2f} A"
    return f"The battery is {at}; empty in about {_hm(hours)}: {how}, at the present draw."


def _hm(hours: float) -> str:
    minutes = round(hours * 60)
    return f"{minutes // 60} h {minutes % 60:02d} min" if minutes >= 60 else f"{minutes} min"


UNMEASURED_AT_ZERO = ("temperature", "charge", "capacity", "design_capacity")


def battery_figure(values: dict, key: str) -> float | None:
    """A BatteryState figure; None when unmeasured: NaN by the message's convention, or 0.0
    where a robot leaves it unset (a TurtleBot3: temperature, charge, capacity; its current
    too when nothing of the charge is measured)."""
    v = values.get(key)
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    if not math.isfinite(f) or (f == 0.0 and key in UNMEASURED_AT_ZERO):
        return None
    if key == "current" and f == 0.0 and not battery_figure(values, "charge"):
        return None
    return f
