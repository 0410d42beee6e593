"""`ros2 service list` (ros2service/verb/list.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-services", action="store_true")
    p.add_argument("--include-hidden-services", action="store_true")
    strategy(p)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import list_text

    return list_text(t.graph("service"), c.parsed.flags)


VERB = Verb(("service", "list"), arguments, run)
