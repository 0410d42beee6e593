"""`ros2 action info` (ros2action/verb/info.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("action_name")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count", action="store_true")


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import Checked, action_spec

    return Checked(cmd.text, cmd, True, type=action_spec(cmd, catalog).type)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    servers = t.action_servers(c.named)
    lines = [f"Action: {c.named}", "Action clients: 0", f"Action servers: {len(servers)}"]
    return "\n".join(lines + [f"    {s}" for s in servers]) + "\n", {"servers": servers}


VERB = Verb(("action", "info"), arguments, run, check)
