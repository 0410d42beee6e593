"""`ros2 param list` (ros2param/verb/list.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("node_name", nargs="?")
    p.add_argument("--filter")
    p.add_argument("--include-hidden-nodes", action="store_true")
    p.add_argument("--param-prefixes", nargs="+", default=[])
    p.add_argument("--param-type", action="store_true")
    strategy(p)


def check(cmd, catalog):
    import re

    from astiop.ros2.interfaces import InterfaceError
    from astiop.ros2.verbs.checks import Checked, param_node

    param_node(cmd, catalog)
    try:
        re.compile(cmd.options.get("filter") or "")
    except re.error as exc:
        raise InterfaceError(f"--filter is not a regular expression: {exc}") from None
    return Checked(cmd.text, cmd, True)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import param_list_text

    node = c.parsed.args.get("node")
    params = t.list_params(node, timeout)
    return param_list_text(params, node, c.parsed.flags, c.parsed.options)


VERB = Verb(("param", "list"), arguments, run, check)
