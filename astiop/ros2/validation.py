"""Before anything runs: the command parses, names exist, types match, values fit the fields."""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass, field, replace
from typing import Any

from astiop.ros2.catalog import Catalog, ServiceSpec
from astiop.ros2.grammar import CommandSyntaxError, Ros2Command, parse
from astiop.ros2.interfaces import InterfaceError, fill, known_type, normalize_type

MAX_PUBLISH_S = 30.0


@dataclass(frozen=True)
class Checked:
    text: str
    command: Ros2Command | None
    valid: bool
    reason: str = ""
    kind: str = "read"  # read | actuate
    type: str | None = None  # the resolved interface type, where one applies
    message: dict[str, Any] | None = None  # checked values with defaults filled
    notes: tuple[str, ...] = field(default_factory=tuple)
    namespace: str = ""  # the robot's: names were resolved inside it

    @property
    def local_name(self) -> str | None:
        """The command's name inside the robot's namespace (/goto_position for
        /astibot_3/goto_position): what the ASTIbot's own names are compared with."""
        name = self.command.name if self.command else None
        if name and self.namespace and name.startswith(self.namespace + "/"):
            return name[len(self.namespace) :]
        return name


def _suggest(name: str, known, avoid: set[str] | frozenset = frozenset()) -> str:
    """A close name the robot has; `avoid`: names never offered (one that moves the robot for
    one that reads it: /goal_pose for /robot_pose)."""
    close = difflib.get_close_matches(name, [k for k in known if k not in avoid], n=1, cutoff=0.5)
    return f"; did you mean {close[0]}?" if close else ""


def _check_type(given: str | None, expected: str, what: str) -> None:
    if given and normalize_type(given) != expected:
        raise InterfaceError(f"{what} has type {expected}, not {given}")


def validate(text: str, catalog: Catalog, distro: str | None = None) -> Checked:
    try:
        cmd = parse(text, distro)
    except CommandSyntaxError as exc:
        return Checked(text, None, False, str(exc))
    namespace = catalog.profile.namespace if catalog.profile is not None else ""
    typed, cmd = cmd, in_namespace(cmd, catalog, namespace)
    resolved = () if cmd is typed else (f"{_named(typed)} is {_named(cmd)} on this robot",)
    try:
        checked = _validate(cmd, catalog)
    except (InterfaceError, CommandSyntaxError) as exc:
        return Checked(text, cmd, False, str(exc), namespace=namespace)
    return replace(checked, namespace=namespace, notes=(*resolved, *checked.notes))


def _named(cmd: Ros2Command) -> str:
    return cmd.args["node"] if cmd.verb == "param" else cmd.name


def in_namespace(cmd: Ros2Command, catalog: Catalog, namespace: str) -> Ros2Command:
    """A name the robot has only inside its namespace is read as that one (/goto_position is
    /astibot_3/goto_position on the robot under /astibot_3), as a relative name resolves in
    ROS 2: the commands the rules and the model write in a robot's own names reach it."""
    if not namespace:
        return cmd
    tables = {"topic": catalog.topics, "service": catalog.services, "action": catalog.actions}
    known = tables.get(cmd.verb, catalog.nodes if cmd.verb in ("node", "param") else None)
    key = "node" if cmd.verb == "param" else "name"
    name = cmd.args.get(key)
    if known is None or not name or name in known:
        return cmd
    inside = namespace + name
    is_cancel = cmd.verb == "service" and cancel_service(catalog, inside) is not None
    if inside not in known and not is_cancel:
        return cmd
    return replace(cmd, args={**cmd.args, key: inside})


def moving_topics(catalog: Catalog) -> set[str]:
    """The topics that move the robot: what it listens to, its velocity command, a goal topic,
    and by convention any goal, initial pose or velocity command (Nav2's /goal_pose,
    /initialpose, /cmd_vel_nav)."""
    words = ("goal", "initialpose", "cmd_vel")
    names = {
        t.name for t in catalog.topics.values() if t.actuating or any(w in t.name for w in words)
    }
    profile = catalog.profile
    if profile is not None:
        names.add(profile.name("velocity_command") or "")
        if profile.kind("navigation") == "topic":
            names.add(profile.name("navigation") or "")
    return names


def _topic(cmd: Ros2Command, catalog: Catalog):
    spec = catalog.topics.get(cmd.name)
    if spec is None:
        avoid = moving_topics(catalog) if cmd.sub != "pub" else frozenset()
        raise InterfaceError(
            f"there is no topic {cmd.name} on this robot"
            + _suggest(cmd.name, catalog.topics, avoid)
            + " (ros2 topic list shows them)"
        )
    return spec


def _validate(cmd: Ros2Command, catalog: Catalog) -> Checked:
    key, text = cmd.key, cmd.text
    if key in (("topic", "info"), ("topic", "type"), ("topic", "hz"), ("topic", "echo")):
        spec = _topic(cmd, catalog)
        given = cmd.args.get("type")
        if given and given.startswith("-"):  # argparse took it for the message type
            raise InterfaceError(
                f"'ros2 topic echo' has no {given} option (ros2 would read it as the message "
                "type and wait); read one message with --once"
            )
        _check_type(given, spec.type, spec.name)
        return Checked(text, cmd, True, type=spec.type)
    if key == ("topic", "pub"):
        spec = _topic(cmd, catalog)
        velocity = catalog.profile.name("velocity_command") if catalog.profile else "/cmd_vel"
        goal = catalog.profile.name("navigation") if catalog.profile else None  # a /goal_pose
        if not spec.subscriber and spec.name not in (velocity, goal):
            raise InterfaceError(
                f"nothing on the robot listens to {spec.name}; the only topic "
                f"you may publish to is {velocity or '/cmd_vel'}"
            )
        _check_type(cmd.args["type"], spec.type, spec.name)
        if "once" not in cmd.flags and "times" not in cmd.options:
            raise InterfaceError("add --once or -t TIMES: astiop does not publish forever")
        rate = cmd.options.get("rate", 1.0)
        times = 1 if "once" in cmd.flags else cmd.options["times"]
        if rate <= 0 or rate > 50:
            raise InterfaceError(f"-r must be within 0..50 Hz, got {rate}")
        if times < 1 or (times - 1) / rate > MAX_PUBLISH_S:
            raise InterfaceError(
                f"-t {times} at {rate:g} Hz would publish for longer than {MAX_PUBLISH_S:g} s"
            )
        msg = fill(spec.type, cmd.args.get("values"))
        return Checked(text, cmd, True, kind="actuate", type=spec.type, message=msg)
    if key in (("service", "type"), ("service", "call")):
        spec = catalog.services.get(cmd.name) or cancel_service(catalog, cmd.name or "")
        if spec is None:
            raise InterfaceError(
                f"there is no service {cmd.name} on this robot"
                + _suggest(cmd.name, catalog.services)
                + " (ros2 service list shows them)"
            )
        if key == ("service", "type"):
            return Checked(text, cmd, True, type=spec.type)
        given = cmd.args.get("type", "")
        if given.startswith("{") or ":" in given:  # the values, where the type belongs
            raise InterfaceError(
                f"ros2 service call needs the service type before the values: "
                f'ros2 service call {spec.name} {spec.type} "{given}"'
            )
        _check_type(given, spec.type, spec.name)
        if not known_type(spec.type):
            raise InterfaceError(f"astiop cannot check requests of type {spec.type}")
        msg = fill(spec.type, cmd.args.get("values"), part=0)
        kind = "actuate" if spec.actuating else "read"
        return Checked(text, cmd, True, kind=kind, type=spec.type, message=msg)
    if key in (("action", "info"), ("action", "send_goal")):
        spec = catalog.actions.get(cmd.name)
        if spec is None:
            raise InterfaceError(
                f"there is no action {cmd.name} on this robot" + _suggest(cmd.name, catalog.actions)
            )
        if key == ("action", "info"):
            return Checked(text, cmd, True, type=spec.type)
        _check_type(cmd.args["type"], spec.type, spec.name)
        msg = fill(spec.type, cmd.args.get("values"), part=0)
        notes: tuple[str, ...] = ()
        header = msg.get("pose", {}).get("header") if isinstance(msg.get("pose"), dict) else None
        if header is not None and not header.get("frame_id"):
            header["frame_id"] = "map"  # Nav2 cannot transform a goal with no frame
            notes = ("the goal's header.frame_id was empty: set to map",)
        return Checked(text, cmd, True, "", "actuate", spec.type, msg, notes)
    if key == ("node", "info") and cmd.name not in catalog.nodes:
        raise InterfaceError(f"there is no node {cmd.name}" + _suggest(cmd.name, catalog.nodes))
    if key == ("interface", "show"):
        name = cmd.args["type"]
        if name.count("/") != 2:
            raise InterfaceError(
                f"ros2 interface show needs the full name pkg/msg/Name (or srv, action), "
                f"not '{name}'"
                + (f"; did you mean {normalize_type(name)}?" if known_type(name) else "")
            )
        if not known_type(name):
            raise InterfaceError(f"unknown interface type {name}")
    if cmd.verb == "param":
        return _validate_param(cmd, catalog)
    return Checked(text, cmd, True)


def _validate_param(cmd: Ros2Command, catalog: Catalog) -> Checked:
    node = cmd.args.get("node")
    if node and node not in catalog.nodes:
        raise InterfaceError(f"there is no node {node}" + _suggest(node, catalog.nodes))
    if cmd.sub == "list":
        try:
            re.compile(cmd.options.get("filter") or "")
        except re.error as exc:
            raise InterfaceError(f"--filter is not a regular expression: {exc}") from None
        return Checked(cmd.text, cmd, True)
    spec = catalog.params.get((node, cmd.args["param"]))
    if spec is None:
        names = [p for n, p in catalog.params if n == node]
        raise InterfaceError(
            f"node {node} has no parameter '{cmd.args['param']}'"
            + (f" (it has: {', '.join(names)})" if names else "")
        )
    if cmd.sub == "get":
        return Checked(cmd.text, cmd, True)
    if not spec.writable:
        raise InterfaceError(f"parameter {spec.name} of {node} is read-only")
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


CANCEL_SUFFIX = "/_action/cancel_goal"  # rcl_action's hidden service of every action server


def cancel_service(catalog: Catalog, name: str) -> ServiceSpec | None:
    """An action's hidden cancel service (`ros2 service list` hides it; it is on the graph with
    every action server): a stop on a robot with no stop service (Nav2) cancels its goals."""
    action = catalog.actions.get(name.removesuffix(CANCEL_SUFFIX))
    if not name.endswith(CANCEL_SUFFIX) or action is None:
        return None
    return ServiceSpec(
        name, "action_msgs/srv/CancelGoal", action.node, True, needs_confirmation=False
    )


# Services that only ever make the robot safer: never held by the e-stop, never confirmed
# (under any namespace: /tb3_1/stop).
ALWAYS_ALLOWED = {"stop"}


def always_allowed(checked: Checked) -> bool:
    """A call of the robot's stop service (under any namespace), or a cancel of an action's
    goals: only ever makes it safer."""
    cmd = checked.command
    if cmd is None or cmd.key != ("service", "call"):
        return False
    name = cmd.name or ""
    return name.rsplit("/", 1)[-1] in ALWAYS_ALLOWED or name.endswith(CANCEL_SUFFIX)
