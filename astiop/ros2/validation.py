"""Before anything runs: the command parses, names exist, types match, values fit the fields
(each verb's own checks are in its module, astiop/ros2/verbs/)."""

from __future__ import annotations

from collections.abc import Container
from dataclasses import replace

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import CommandSyntaxError, Ros2Command, parse
from astiop.ros2.interfaces import InterfaceError
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.checks import (  # noqa: F401 - their callers read them here
    CANCEL_SUFFIX,
    Checked,
    cancel_service,
)


def validate(text: str, catalog: Catalog, distro: str | None = None) -> Checked:
    try:
        cmd = parse(text, distro)
    except CommandSyntaxError as exc:
        return Checked(text, None, False, str(exc))
    namespace = catalog.profile.namespace if catalog.profile is not None else ""
    typed, cmd = cmd, in_namespace(cmd, catalog, namespace)
    resolved = () if cmd is typed else (f"{_named(typed)} is {_named(cmd)} on this robot",)
    try:
        checked = VERBS[cmd.key].check(cmd, catalog)
    except (InterfaceError, CommandSyntaxError) as exc:
        return Checked(text, cmd, False, str(exc), namespace=namespace)
    return replace(checked, namespace=namespace, notes=(*resolved, *checked.notes))


def _named(cmd: Ros2Command) -> str:
    return cmd.args["node"] if cmd.command == "param" else (cmd.name or "")


def in_namespace(cmd: Ros2Command, catalog: Catalog, namespace: str) -> Ros2Command:
    """A name the robot has only inside its namespace is read as that one (/goto_position is
    /astibot_3/goto_position on the robot under /astibot_3), as a relative name resolves in
    ROS 2: the commands the rules and the model write in a robot's own names reach it."""
    if not namespace:
        return cmd
    tables: dict[str, Container[str]] = {
        "topic": catalog.topics,
        "service": catalog.services,
        "action": catalog.actions,
    }
    known: Container[str] | None = tables.get(
        cmd.command, catalog.nodes if cmd.command in ("node", "param") else None
    )
    key = "node" if cmd.command == "param" else "name"
    name = cmd.args.get(key)
    if known is None or not name or name in known:
        return cmd
    inside = namespace + name
    is_cancel = cmd.command == "service" and cancel_service(catalog, inside) is not None
    if inside not in known and not is_cancel:
        return cmd
    return replace(cmd, args={**cmd.args, key: inside})


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
