"""`ros2 node info` (ros2node/verb/info.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("node_name")
    p.add_argument("--include-hidden", action="store_true")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.interfaces import InterfaceError
    from astiop.ros2.verbs.checks import Checked, suggest

    if cmd.name not in catalog.nodes:
        raise InterfaceError(f"there is no node {cmd.name}" + suggest(cmd.name, catalog.nodes))
    return Checked(cmd.text, cmd, True)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import node_info_text

    info = t.node_info(c.named)
    return node_info_text(c.named, info), info


VERB = Verb(("node", "info"), arguments, run, check)
