"""`ros2 action list` (ros2action/verb/list.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-actions", action="store_true")


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import list_text

    return list_text(t.graph("action"), c.parsed.flags)


VERB = Verb(("action", "list"), arguments, run)
