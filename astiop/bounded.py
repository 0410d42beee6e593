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


def one_line(text: object, limit: int = 300) -> str:
    """Any message as one line: whitespace (newlines included) collapsed, length capped."""
    return " ".join(str(text).split())[:limit]


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


_QUOTED = re.compile(r"'(?:[^']|'')*'|\"(?:[^\"\\]|\\.)*\"")
_ANCHOR_OR_ALIAS = re.compile(r"(?:^|[\s\[{,:])[&*][^\s,\]}]")
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when PyYAML has it


def load_yaml(text: str) -> Any:
    """YAML values from one command line: no anchors or aliases (no alias bombs), at most
    MAX_DEPTH deep, numbers Python can hold. Linear: both checks are one pass."""
    if nesting(text) > MAX_DEPTH:
        raise BoundsError(f"the values nest deeper than {MAX_DEPTH} levels")
    if _ANCHOR_OR_ALIAS.search(_QUOTED.sub("''", text)):
        raise BoundsError("YAML anchors and aliases (&name, *name) are not allowed in values")
    try:
        return yaml.load(text, Loader=_LOADER)  # noqa: S506 (a safe loader)
    except ValueError as exc:  # an integer past Python's digit limit
        raise BoundsError(f"a number in the values cannot be read ({str(exc)[:80]})") from None


def load_json_object(text: str, start: int) -> tuple[Any, int]:
    """json.raw_decode within MAX_DEPTH and Python's number limits."""
    try:
        return json.JSONDecoder().raw_decode(text, start)
    except (ValueError, RecursionError) as exc:
        if isinstance(exc, json.JSONDecodeError):
            raise
        raise json.JSONDecodeError(f"unreadable ({str(exc)[:60]})", text, start) from None
