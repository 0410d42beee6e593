"""`ros2 topic type` (ros2topic/verb/type.py)."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def run(t, c, timeout: float):
    return c.type + "\n", c.type


VERB = Verb(("topic", "type"), arguments, run, check)
