"""`ros2 node list` (ros2node/verb/list.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("-a", "--all", action="store_true")
    p.add_argument("-c", "--count-nodes", action="store_true")
    strategy(p)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    names = [name for name, _ in t.graph("node")]
    return "".join(f"{n}\n" for n in names), names


VERB = Verb(("node", "list"), arguments, run)
