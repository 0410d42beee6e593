"""A ros2 command as astiop parsed it: its verb, names, flags and options, and what was typed."""

from __future__ import annotations

import shlex
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Ros2Command:
    text: str
    command: str  # ros2cli's command: topic, service, action, param, node, interface
    verb: str  # and its verb: echo, call, send_goal, ...
    args: dict[str, Any]  # name (full), type, values (parsed YAML), node, param, value
    flags: frozenset[str]
    options: dict[str, Any]
    argv: tuple[str, ...]  # what was typed after `ros2`
    distro: str = "jazzy"

    @property
    def key(self) -> tuple[str, str]:
        return (self.command, self.verb)

    @property
    def name(self) -> str | None:
        return self.args.get("name")

    def display(self) -> str:
        return "ros2 " + shlex.join(self.argv)
