"""`ros2 interface list` (ros2interface/verb/list.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("-m", "--only-msgs", action="store_true")
    p.add_argument("-s", "--only-srvs", action="store_true")
    p.add_argument("-a", "--only-actions", action="store_true")


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import interface_list_text

    return interface_list_text(t.interfaces(), c.parsed.flags)


VERB = Verb(("interface", "list"), arguments, run)
