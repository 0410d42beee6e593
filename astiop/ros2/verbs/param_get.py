"""`ros2 param get` (ros2param/verb/get.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


WORDS = {bool: "Boolean", int: "Integer", float: "Double", str: "String"}


def arguments(p, distro: str) -> None:
    p.add_argument("node_name")
    p.add_argument("--include-hidden-nodes", action="store_true")
    p.add_argument("parameter_name")
    p.add_argument("--hide-type", action="store_true")
    if distro != "humble":
        p.add_argument("--timeout", type=int, default=1)
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import Checked, param_spec

    param_spec(cmd, catalog)
    return Checked(cmd.text, cmd, True)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    value = t.get_param(c.parsed.args["node"], c.parsed.args["param"], timeout)
    return f"{WORDS[type(value)]} value is: {value}\n", {"value": value}


VERB = Verb(("param", "get"), arguments, run, check)
