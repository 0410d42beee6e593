"""`ros2 topic pub` (ros2topic/verb/pub.py): astiop publishes --once or -t TIMES, never forever."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import (
    nonnegative_int,
    positive_float,
    qos,
    values_or_stdin,
)
from astiop.ros2.verbs.base import PUBLISH, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


MAX_RATE_HZ = 50


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    p.add_argument("message_type")
    values_or_stdin(p, distro, "values")
    p.add_argument("-r", "--rate", type=positive_float, default=1.0)
    p.add_argument("-p", "--print", type=int, default=1)
    g = p.add_mutually_exclusive_group()
    g.add_argument("-1", "--once", action="store_true")
    g.add_argument("-t", "--times", type=nonnegative_int, default=0)
    p.add_argument("-w", "--wait-matching-subscriptions", type=nonnegative_int)
    if distro != "humble":
        p.add_argument("--max-wait-time-secs", type=positive_float)
    p.add_argument("--keep-alive", type=positive_float, default=0.1)
    p.add_argument("-n", "--node-name")
    qos(p, distro)
    p.add_argument("--use-sim-time", action="store_true")


def normalize(ns: dict, options: dict) -> None:
    if not ns.get("times"):
        options.pop("times", None)  # 0: forever, which astiop refuses


def check(cmd, catalog):
    from astiop.ros2.interfaces import InterfaceError, fill
    from astiop.ros2.verbs.checks import MAX_PUBLISH_S, Checked, check_type, topic_spec

    spec = topic_spec(cmd, catalog)
    velocity = catalog.profile.name("velocity_command") if catalog.profile else "/cmd_vel"
    goal = catalog.profile.name("navigation") if catalog.profile else None  # a /goal_pose
    if not spec.subscriber and spec.name not in (velocity, goal):
        raise InterfaceError(
            f"nothing on the robot listens to {spec.name}; the only topic "
            f"you may publish to is {velocity or '/cmd_vel'}"
        )
    check_type(cmd.args["type"], spec.type, spec.name)
    if "once" not in cmd.flags and "times" not in cmd.options:
        raise InterfaceError("add --once or -t TIMES: astiop does not publish forever")
    rate = cmd.options.get("rate", 1.0)
    times = 1 if "once" in cmd.flags else cmd.options["times"]
    if rate <= 0 or rate > MAX_RATE_HZ:
        raise InterfaceError(f"-r must be within 0..{MAX_RATE_HZ} Hz, got {rate}")
    if times < 1 or (times - 1) / rate > MAX_PUBLISH_S:
        raise InterfaceError(
            f"-t {times} at {rate:g} Hz would publish for longer than {MAX_PUBLISH_S:g} s"
        )
    msg = fill(spec.type, cmd.args.get("values"))
    return Checked(cmd.text, cmd, True, kind="actuate", type=spec.type, message=msg)


def lasts(cmd) -> float:
    """-t TIMES at -r RATE publishes for this long."""
    if "once" in cmd.flags:
        return 0.0
    return (cmd.options["times"] - 1) / cmd.options.get("rate", 1.0)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    return t.publish(c, timeout)


VERB = Verb(
    ("topic", "pub"),
    arguments,
    run,
    check,
    runs_as=PUBLISH,
    example='ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist "{linear: {x: 0.2}}"',
    values_from="values",
    normalize=normalize,
    duration=lasts,
)
