"""`ros2 param set` (ros2param/verb/set.py): a number within the parameter's declared range."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("node_name")
    p.add_argument("--include-hidden-nodes", action="store_true")
    p.add_argument("parameter_name")
    p.add_argument("value")
    if distro != "humble":
        p.add_argument("--timeout", type=int, default=1)
    strategy(p)


def check(cmd, catalog):
    import math

    from astiop.ros2.interfaces import InterfaceError
    from astiop.ros2.verbs.checks import Checked, param_spec

    spec = param_spec(cmd, catalog)
    node = cmd.args["node"]
    if not spec.writable:
        mine = sorted(p for (n, p), s in catalog.params.items() if n == node and s.writable)
        said = f" (astiop writes: {', '.join(mine)})" if mine else ""
        raise InterfaceError(f"parameter {spec.name} of {node} is read-only{said}")
    # typed by the parameter's declared type: rclcpp refuses `1` for a double
    try:
        value = float(cmd.args["value"])
    except ValueError:
        raise InterfaceError(f"{spec.name} takes a number, got '{cmd.args['value']}'") from None
    if not math.isfinite(value):
        raise InterfaceError(f"{spec.name} takes a finite number, got '{cmd.args['value']}'")
    if isinstance(spec.value, int) and not isinstance(spec.value, bool):
        if not value.is_integer():
            raise InterfaceError(f"{spec.name} is an integer parameter, got {cmd.args['value']}")
        value = int(value)
    if not (spec.minimum <= value <= spec.maximum):
        raise InterfaceError(f"{spec.name} must be within {spec.minimum}..{spec.maximum}")
    return Checked(cmd.text, cmd, True, kind="actuate", message={"value": value})


def run(t: Transport, c: Checked, timeout: float) -> Output:
    node, param, value = c.parsed.args["node"], c.parsed.args["param"], c.values["value"]
    reason = t.set_param(node, param, value, timeout)
    return "Set parameter successful" + (f": {reason}" if reason else "") + "\n", {"value": value}


VERB = Verb(
    ("param", "set"),
    arguments,
    run,
    check,
    example="ros2 param set /astibot_base max_linear_speed 0.5",
)
