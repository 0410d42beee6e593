"""`ros2 param get` (ros2param/verb/get.py)."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb

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


def run(t, c, timeout: float):
    value = t.get_param(c.command.args["node"], c.command.args["param"], timeout)
    return f"{WORDS[type(value)]} value is: {value}\n", {"value": value}


VERB = Verb(("param", "get"), arguments, run, check)
