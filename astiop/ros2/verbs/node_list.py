"""`ros2 node list` (ros2node/verb/list.py)."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    p.add_argument("-a", "--all", action="store_true")
    p.add_argument("-c", "--count-nodes", action="store_true")
    strategy(p)


def run(t, c, timeout: float):
    names = [name for name, _ in t.graph("node")]
    return "".join(f"{n}\n" for n in names), names


VERB = Verb(("node", "list"), arguments, run)
