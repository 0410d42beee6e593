"""`ros2 topic hz` (ros2topic/verb/hz.py): astiop prints its first two windows, a second apart."""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import positive_int, strategy
from astiop.ros2.verbs.base import SAMPLE, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


WINDOWS = 2
ROS2_WINDOW = 10000  # ros2's default --window


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    p.add_argument("--window", "-w", dest="window_size", type=positive_int, default=ROS2_WINDOW)
    p.add_argument("--filter", dest="filter_expr")
    p.add_argument("--wall-time", dest="use_wtime", action="store_true")
    strategy(p)


def normalize(ns: dict, options: dict) -> None:
    if ns.get("window_size") == ROS2_WINDOW:
        options.pop("window", None)  # ros2's default: astiop keeps its own short window


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def windows(times: list[float], window: int | None = None) -> list[tuple[float, list[float]]]:
    """ros2 hz's prints: (rate, the periods it was taken over), the first once two messages
    came, each next when a second has passed since the one before."""
    out, printed_at = [], None
    for k in range(1, len(times)):
        if printed_at is None:
            printed_at = times[k]
            continue
        if times[k] < printed_at + 1.0:
            continue
        seen = times[: k + 1][-(window + 1) :] if window else times[: k + 1]
        deltas = [b - a for a, b in zip(seen, seen[1:])]
        mean = sum(deltas) / len(deltas)
        out.append((1.0 / mean if mean > 0 else 0.0, deltas))
        printed_at = times[k]
    return out


def run(t: Transport, c: Checked, timeout: float) -> Output:
    window = c.parsed.options.get("window")
    arrivals = t.samples(
        c.named, c.interface, lambda got: len(windows([a for a, _ in got], window)) >= WINDOWS,
        timeout,
    )  # fmt: skip
    found = windows([a for a, _ in arrivals], window)[:WINDOWS]
    if not found:
        raise VERB.nothing_came(c.named, timeout)
    lines = []
    for rate, deltas in found:
        mean = sum(deltas) / len(deltas)
        std = math.sqrt(sum((d - mean) ** 2 for d in deltas) / len(deltas))
        lines.append(
            f"average rate: {rate:.3f}\n\tmin: {min(deltas):.3f}s max: {max(deltas):.3f}s "
            f"std dev: {std:.5f}s window: {len(deltas)}"
        )
    return "\n".join(lines) + "\n", read("\n".join(lines))


def enough(out: str) -> bool:
    return out.count("average rate:") >= WINDOWS


def read(out: str) -> dict | None:
    rates = re.findall(r"average rate: ([0-9.]+)", out)
    return {"average_rate": float(rates[-1]), "windows": len(rates)} if rates else None


VERB = Verb(
    ("topic", "hz"),
    arguments,
    run,
    check,
    runs_as=SAMPLE,
    options={"window_size": "window"},
    normalize=normalize,
    measures=True,
    output_complete=enough,
    parse_output=read,
    when_silent="no rate",
)
