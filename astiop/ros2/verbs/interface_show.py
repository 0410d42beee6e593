"""`ros2 interface show` (ros2interface/verb/show.py), from the definitions astiop knows."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("type")
    p.add_argument("--all-comments", action="store_true")
    p.add_argument("--no-comments", action="store_true")


def check(cmd, catalog):
    from astiop.ros2.interfaces import InterfaceError, known_type, normalize_type
    from astiop.ros2.verbs.checks import Checked

    name = cmd.args["type"]
    if name.count("/") != 2:
        raise InterfaceError(
            f"ros2 interface show needs the full name pkg/msg/Name (or srv, action), "
            f"not '{name}'"
            + (f"; did you mean {normalize_type(name)}?" if known_type(name) else "")
        )
    if not known_type(name):
        raise InterfaceError(f"unknown interface type {name}")
    return Checked(cmd.text, cmd, True)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.interfaces import interface_show

    return interface_show(c.parsed.args["type"]), None


VERB = Verb(
    ("interface", "show"),
    arguments,
    run,
    check,
    example="ros2 interface show sensor_msgs/msg/LaserScan",
)
