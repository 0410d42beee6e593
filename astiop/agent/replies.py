"""Reading a model's reply: the JSON object in it (fenced, bare or after prose), or ros2 lines."""

from __future__ import annotations

import json
import re
from typing import Any

from astiop.agent.tools import Tool, ToolError, render
from astiop.bounded import MAX_DEPTH, MAX_REPLY_CHARS, load_json_object, nesting


class ReplyError(ValueError):
    """The reply holds no usable plan; the message is fed back for one repair."""


def find_json_object(text: str) -> dict[str, Any] | None:
    """The first JSON object in the reply; a reply past the size or depth cap is refused."""
    if len(text) > MAX_REPLY_CHARS:
        raise ReplyError(f"the reply is {len(text):,} characters; the cap is {MAX_REPLY_CHARS:,}")
    if nesting(text) > MAX_DEPTH:
        raise ReplyError(f"the reply nests deeper than {MAX_DEPTH} levels")
    for match in re.finditer(r"\{", text):
        try:
            obj, _ = load_json_object(text, match.start())
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
    lines = [ln.strip().strip("`").strip() for ln in text.splitlines()[:200]]
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
