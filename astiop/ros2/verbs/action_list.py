"""`ros2 action list` (ros2action/verb/list.py)."""

from __future__ import annotations

from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-actions", action="store_true")


def run(t, c, timeout: float):
    from astiop.ros2.printing import list_text

    return list_text(t.graph("action"), c.command.flags)


VERB = Verb(("action", "list"), arguments, run)
