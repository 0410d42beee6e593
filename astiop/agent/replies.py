"""Reading a model's reply: the JSON object in it (fenced, bare or after prose), or ros2 lines."""

from __future__ import annotations

import json
import re
from typing import Any

from astiop.agent.tools import Tool, ToolError, render


class ReplyError(ValueError):
    """The reply holds no usable plan; the message is fed back for one repair."""


def find_json_object(text: str) -> dict[str, Any] | None:
    decoder = json.JSONDecoder()
    for match in re.finditer(r"\{", text):
        try:
            obj, _ = decoder.raw_decode(text, match.start())
        except json.JSONDecodeError:
            continue
        if isinstance(obj, dict):
            return obj
    return None


def commands_from_reply(text: str) -> list[str]:
    """Command mode: {"commands": [...]} or {"command": "..."}, else lines that start with ros2."""
    obj = find_json_object(text)
    if obj is not None:
        cmds = obj.get("commands", obj.get("command"))
        if isinstance(cmds, str):
            cmds = [cmds]
        if isinstance(cmds, list) and all(isinstance(c, str) for c in cmds):
            return [c.strip() for c in cmds if c.strip()][:3]
    lines = [ln.strip().strip("`").strip() for ln in text.splitlines()]
    found = [ln for ln in lines if ln.startswith("ros2 ")]
    if found:
        return found[:3]
    if obj is None:
        raise ReplyError('the reply was not JSON; answer with {"commands": ["ros2 ..."]}')
    raise ReplyError('the JSON had no "commands" list of strings')


def steps_from_reply(text: str, tools: list[Tool]) -> list[str]:
    """Tool mode: {"steps": [{"tool": ...}]} or a single {"tool": ...}; rendered commands."""
    obj = find_json_object(text)
    if obj is None:
        raise ReplyError('the reply was not JSON; answer with {"steps": [{"tool": "..."}]}')
    steps = obj.get("steps", [obj] if "tool" in obj else None)
    if not isinstance(steps, list) or not steps:
        raise ReplyError('the JSON had no "steps" list')
    commands = []
    for step in steps[:3]:
        try:
            cmd = render(step, tools)
        except ToolError as exc:
            raise ReplyError(str(exc)) from None
        if cmd:
            commands.append(cmd)
    return commands
