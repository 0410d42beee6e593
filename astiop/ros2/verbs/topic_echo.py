"""`ros2 topic echo` (ros2topic/verb/echo.py): astiop reads one message (--once)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import nonnegative_int, positive_float, qos, strategy
from astiop.ros2.verbs.base import TAKE, BackendError, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    p.add_argument("message_type", nargs="?")
    qos(p, distro)
    p.add_argument("--csv", action="store_true")
    p.add_argument("--field")
    p.add_argument("--full-length", "-f", action="store_true")
    p.add_argument("--truncate-length", "-l", type=nonnegative_int, default=128)
    p.add_argument("--no-arr", action="store_true")
    p.add_argument("--no-str", action="store_true")
    p.add_argument("--flow-style", action="store_true")
    p.add_argument("--no-lost-messages", action="store_true")
    p.add_argument("--raw", action="store_true")
    p.add_argument("--filter", dest="filter_expr")
    p.add_argument("--once", action="store_true")
    if distro == "humble":
        p.add_argument("--lost-messages", action="store_true")
    else:
        p.add_argument("--timeout", type=positive_float)
        p.add_argument("--include-message-info", "-i", action="store_true")
    strategy(p)


def normalize(ns: dict, options: dict) -> None:
    if options.get("truncate") == 128:  # ros2's default
        options.pop("truncate")


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    from astiop.ros2.printing import echo_text, ros2cli_yaml

    values = t.take(c, c.parsed.options.get("timeout", timeout))
    field = c.parsed.options.get("field")
    if field:
        for part in field.split("."):
            if not isinstance(values, dict) or part not in values:
                raise BackendError(f"{c.named} has no field {field}")
            values = values[part]
        return ros2cli_yaml(values) + "---\n", values
    return echo_text(values, c.command), values


VERB = Verb(
    ("topic", "echo"),
    arguments,
    run,
    check,
    runs_as=TAKE,
    example="ros2 topic echo /battery_status sensor_msgs/msg/BatteryState --once",
    normalize=normalize,
    measures=True,
)
