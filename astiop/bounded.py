"""Reading what comes from outside (model replies, command arguments, config) within bounds.

Every reader here is linear in its input and refuses, in one line, what is too long, too deep,
or built to blow up: YAML aliases, integers past their type, non-finite numbers.
"""

from __future__ import annotations

import json
import re
from typing import Any

import yaml

MAX_COMMAND_CHARS = 4_096  # one ros2 command line, values included
MAX_REPLY_CHARS = 32_768  # one model reply
MAX_DEPTH = 32  # nesting of YAML or JSON values
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


class BoundsError(ValueError):
    """The input is too long, too deep, or not allowed; nothing was done with it."""


def preview(text: str, limit: int = 60) -> str:
    """A short, printable quote of untrusted text for an error message."""
    shown = escape_controls(text[:limit])
    return repr(shown + ("…" if len(text) > limit else ""))


def escape_controls(text: str) -> str:
    """Control characters (terminal escapes, NUL, bell) shown escaped, never sent raw."""
    return _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)


def has_controls(text: str) -> bool:
    return bool(_CONTROL.search(text.replace("\t", " ")))


def nesting(text: str) -> int:
    """The deepest bracket nesting outside quotes, in one pass."""
    depth = deepest = 0
    quote = None
    escaped = False
    for ch in text:
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\" and quote == '"':
                escaped = True
            elif ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(depth - 1, 0)
    return deepest


class _NoAliasLoader(yaml.SafeLoader):
    """SafeLoader without anchors/aliases (no alias bombs) and with a depth cap."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            raise BoundsError("YAML aliases (*name) are not allowed in values")
        self._depth = getattr(self, "_depth", 0) + 1
        try:
            if self._depth > MAX_DEPTH:
                raise BoundsError(f"the values nest deeper than {MAX_DEPTH} levels")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def anchor_node(self, node):  # anchors are refused with the alias that would use them
        return super().anchor_node(node)


def load_yaml(text: str) -> Any:
    """YAML values from outside: no aliases, at most MAX_DEPTH deep, numbers Python can hold."""
    if nesting(text) > MAX_DEPTH:
        raise BoundsError(f"the values nest deeper than {MAX_DEPTH} levels")
    try:
        return yaml.load(text, Loader=_NoAliasLoader)  # noqa: S506 (a SafeLoader subclass)
    except ValueError as exc:  # BoundsError, or an integer past Python's digit limit
        if isinstance(exc, BoundsError):
            raise
        raise BoundsError(f"a number in the values cannot be read ({str(exc)[:80]})") from None


def load_json_object(text: str, start: int) -> tuple[Any, int]:
    """json.raw_decode within MAX_DEPTH and Python's number limits."""
    try:
        return json.JSONDecoder().raw_decode(text, start)
    except (ValueError, RecursionError) as exc:
        if isinstance(exc, json.JSONDecodeError):
            raise
        raise json.JSONDecodeError(f"unreadable ({str(exc)[:60]})", text, start) from None
