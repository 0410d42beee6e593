"""`ros2 topic type` (ros2topic/verb/type.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    return c.interface + "\n", c.interface


VERB = Verb(("topic", "type"), arguments, run, check)
