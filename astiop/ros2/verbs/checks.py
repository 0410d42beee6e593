"""What a verb's checks share: the checked command, a close name to suggest, a type that must
match, the topic looked up, the topics that move the robot, an action's hidden cancel service."""

from __future__ import annotations

import difflib
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from typing import Any

from astiop.ros2.catalog import Catalog, ServiceSpec
from astiop.ros2.command import Ros2Command
from astiop.ros2.interfaces import InterfaceError, normalize_type
from astiop.ros2.verbs.base import BackendError

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
    def parsed(self) -> Ros2Command:
        """The command a verb runs: only a valid one reaches it, and a valid one has it."""
        if self.command is None:
            raise BackendError(f"not a command: {self.reason or self.text}")
        return self.command

    @property
    def named(self) -> str:
        """The topic, service, action or node the command names; BackendError if none."""
        name = self.parsed.name
        if not name:
            raise BackendError(f"{self.text}: names no topic, service or action")
        return name

    @property
    def interface(self) -> str:
        """The interface type validation resolved for the command (a message, service, action)."""
        if self.type is None:
            raise BackendError(f"{self.text}: no interface type was resolved for it")
        return self.type

    @property
    def values(self) -> dict[str, Any]:
        """The checked values the command sends (its message, request or goal)."""
        if self.message is None:
            raise BackendError(f"{self.text}: it has no values to send")
        return self.message

    @property
    def local_name(self) -> str | None:
        """The command's name inside the robot's namespace (/goto_position for
        /astibot_3/goto_position): what the ASTIbot's own names are compared with."""
        name = self.command.name if self.command else None
        if name and self.namespace and name.startswith(self.namespace + "/"):
            return name[len(self.namespace) :]
        return name


def suggest(name: str | None, known, avoid: AbstractSet[str] = frozenset()) -> str:
    """A close name the robot has; `avoid`: names never offered (one that moves the robot for
    one that reads it: /goal_pose for /robot_pose)."""
    close = difflib.get_close_matches(
        name or "", [k for k in known if k not in avoid], n=1, cutoff=0.5
    )
    return f"; did you mean {close[0]}?" if close else ""


def check_type(given: str | None, expected: str, what: str) -> None:
    if given and normalize_type(given) != expected:
        raise InterfaceError(f"{what} has type {expected}, not {given}")


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


def topic_spec(cmd: Ros2Command, catalog: Catalog):
    spec = catalog.topics.get(cmd.name or "")
    if spec is None:
        avoid = moving_topics(catalog) if cmd.verb != "pub" else frozenset()
        raise InterfaceError(
            f"there is no topic {cmd.name} on this robot"
            + suggest(cmd.name, catalog.topics, avoid)
            + " (ros2 topic list shows them)"
        )
    return spec


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


def checked_topic(cmd: Ros2Command, catalog: Catalog) -> Checked:
    """A verb that reads a topic the robot has (info, type, echo, hz, bw): its type resolved."""
    spec = topic_spec(cmd, catalog)
    given = cmd.args.get("type")
    if given and given.startswith("-"):  # argparse took it for the message type
        raise InterfaceError(
            f"'ros2 topic echo' has no {given} option (ros2 would read it as the message "
            "type and wait); read one message with --once"
        )
    check_type(given, spec.type, spec.name)
    return Checked(cmd.text, cmd, True, type=spec.type)


def service_spec(cmd: Ros2Command, catalog: Catalog) -> ServiceSpec:
    spec = catalog.services.get(cmd.name or "") or cancel_service(catalog, cmd.name or "")
    if spec is None:
        raise InterfaceError(
            f"there is no service {cmd.name} on this robot"
            + suggest(cmd.name, catalog.services)
            + " (ros2 service list shows them)"
        )
    return spec


def action_spec(cmd: Ros2Command, catalog: Catalog):
    spec = catalog.actions.get(cmd.name or "")
    if spec is None:
        raise InterfaceError(
            f"there is no action {cmd.name} on this robot" + suggest(cmd.name, catalog.actions)
        )
    return spec


def param_node(cmd: Ros2Command, catalog: Catalog) -> str | None:
    node = cmd.args.get("node")
    if node and node not in catalog.nodes:
        raise InterfaceError(f"there is no node {node}" + suggest(node, catalog.nodes))
    return node


def param_spec(cmd: Ros2Command, catalog: Catalog):
    node = param_node(cmd, catalog)
    spec = catalog.params.get((node or "", cmd.args["param"]))
    if spec is None:
        names = [p for n, p in catalog.params if n == node]
        raise InterfaceError(
            f"node {node} has no parameter '{cmd.args['param']}'"
            + (f" (it has: {', '.join(names)})" if names else "")
        )
    return spec
