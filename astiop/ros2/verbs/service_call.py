"""`ros2 service call` (ros2service/verb/call.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import values_or_stdin
from astiop.ros2.verbs.base import CALL, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("service_name")
    p.add_argument("service_type")
    values_or_stdin(p, distro, "values")
    p.add_argument("-r", "--rate", type=float)


def check(cmd, catalog):
    from astiop.ros2.interfaces import InterfaceError, fill, known_type
    from astiop.ros2.verbs.checks import Checked, check_type, service_spec

    spec = service_spec(cmd, catalog)
    given = cmd.args.get("type", "")
    if given.startswith("{") or ":" in given:  # the values, where the type belongs
        raise InterfaceError(
            f"ros2 service call needs the service type before the values: "
            f'ros2 service call {spec.name} {spec.type} "{given}"'
        )
    check_type(given, spec.type, spec.name)
    if not known_type(spec.type):
        raise InterfaceError(f"astiop cannot check requests of type {spec.type}")
    msg = fill(spec.type, cmd.args.get("values"), part=0)
    kind = "actuate" if spec.actuating else "read"
    return Checked(cmd.text, cmd, True, kind=kind, type=spec.type, message=msg)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    return t.call(c, timeout)


VERB = Verb(
    ("service", "call"),
    arguments,
    run,
    check,
    runs_as=CALL,
    example="ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'shipping'}\"",
    values_from="values",
)
