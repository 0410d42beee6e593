"""`ros2 service type` (ros2service/verb/type.py)."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    p.add_argument("service_name")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import Checked, service_spec

    return Checked(cmd.text, cmd, True, type=service_spec(cmd, catalog).type)


def run(t, c, timeout: float):
    return c.type + "\n", c.type


VERB = Verb(("service", "type"), arguments, run, check)
