"""`ros2 service type` (ros2service/verb/type.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("service_name")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import Checked, service_spec

    return Checked(cmd.text, cmd, True, type=service_spec(cmd, catalog).type)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    return c.interface + "\n", c.interface


VERB = Verb(("service", "type"), arguments, run, check)
