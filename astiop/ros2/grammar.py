"""The subset of the `ros2` CLI the agent may use, parsed by ros2cli's own argument definitions
for the robot's distro (`ROS_DISTRO`, default jazzy): what parses here parses on the robot.

Anything outside it is refused with the real CLI's error and astiop's suggestion; there is no
path by which other text runs.
"""

from __future__ import annotations

import argparse
import difflib
import re
import shlex
from functools import cache
from typing import Any

import yaml

from astiop.bounded import (
    MAX_COMMAND_CHARS,
    BoundsError,
    has_controls,
    load_yaml,
    preview,
)
from astiop.distro import DISTROS, current_distro  # noqa: F401 - its callers read it here
from astiop.ros2.cli_args import build_parser
from astiop.ros2.command import Ros2Command
from astiop.ros2.verbs import VERBS

SHELL_OPERATORS = {"|", "||", "&", "&&", ";", ";;", ">", ">>", "<", "<<", "$(", "`", "(", ")"}
SUPPORTED = set(VERBS)
ALLOWED = ", ".join(sorted(f"{v} {s}" for v, s in SUPPORTED))
EXAMPLES = {key: verb.example for key, verb in VERBS.items() if verb.example}
# argparse destinations astiop reads, by its own names
_FLAGS = {
    "once": "once",
    "no_arr": "no_arr",
    "no_str": "no_str",
    "show_types": "show_types",
    "feedback": "feedback",
    "full_length": "full_length",
    "flow_style": "flow_style",
    "csv": "csv",
    "verbose": "verbose",
    "count_topics": "count_topics",  # list -c: printed as the count (ros2topic/verb/list.py)
    "count_services": "count_services",
    "count_actions": "count_actions",
    "param_type": "param_type",  # param list --param-type (ros2param/verb/list.py)
    "only_msgs": "only_msgs",  # interface list -m|-s|-a (ros2interface/verb/list.py)
    "only_srvs": "only_srvs",
    "only_actions": "only_actions",
}
_OPTIONS = {
    "param_prefixes": "param_prefixes",
    "filter": "filter",  # param list --filter RE (topic and service lists use filter_expr)
    "rate": "rate",
    "times": "times",
    "timeout": "timeout",
    "print": "print",
    "wait_matching_subscriptions": "wait",
    "truncate_length": "truncate",
    "field": "field",
    "qos_profile": "qos_profile",
    "qos_depth": "qos_depth",
    "qos_history": "qos_history",
    "qos_reliability": "qos_reliability",
    "qos_durability": "qos_durability",
}


class CommandSyntaxError(ValueError):
    """The text is not a command of the supported `ros2` subset for this distro."""


class _Parser(argparse.ArgumentParser):
    """argparse that raises (with a suggestion) instead of printing and exiting."""

    def error(self, message: str):
        raise CommandSyntaxError(f"{self.prog}: error: {message}")

    def exit(self, status=0, message=None):
        raise CommandSyntaxError(f"{self.prog}: asks for help; send a command instead")


@cache
def _parser(distro: str) -> argparse.ArgumentParser:
    return build_parser(distro, _Parser)


def verb_parser(distro: str, key: tuple[str, str]) -> argparse.ArgumentParser:
    parser = _parser(distro)
    for word in key:
        action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = action.choices[word]
    return parser


def _suggest(distro: str, key: tuple[str, str], message: str) -> str:
    """argparse reports unknown options at the root: name the verb and its closest option."""
    m = re.search(r"unrecognized arguments: (\S+)", message)
    if not m:
        return message
    parser = verb_parser(distro, key)
    options = [o for o in parser._option_string_actions if o.startswith("--")]
    close = difflib.get_close_matches(m[1].split("=")[0], options, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]}?" if close else ""
    return message.replace("ros2: error:", f"ros2 {key[0]} {key[1]} ({distro}): error:") + hint


def normalize_name(name: str) -> str:
    name = name.strip()
    return name if name.startswith("/") else "/" + name


def parse_values(text: str) -> dict[str, Any]:
    try:
        value = load_yaml(text) if text.strip() else {}
    except BoundsError as exc:
        raise CommandSyntaxError(f"the values {preview(text)} were refused: {exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise CommandSyntaxError(
            f"the values {preview(text)} are not valid YAML ({mark}); write them as a YAML "
            'mapping, e.g. "{linear: {x: 0.2}}"'
        ) from None
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise CommandSyntaxError(
            f'the values {preview(text)} must be a YAML mapping like "{{x: 1.0}}"'
        )
    return value


def _tokens(text: str) -> list[str]:
    if not isinstance(text, str) or not text.strip():
        raise CommandSyntaxError("the command is empty; send one ros2 command")
    if len(text) > MAX_COMMAND_CHARS:  # checked first: everything after is linear in this
        raise CommandSyntaxError(
            f"the command is {len(text):,} characters; the limit is {MAX_COMMAND_CHARS:,}"
        )
    if has_controls(text.strip()):
        raise CommandSyntaxError(
            f"the command holds control characters ({preview(text.strip(), 40)}); send plain text"
        )
    if "\n" in text.strip():
        raise CommandSyntaxError("send one ros2 command per line")
    try:
        tokens = shlex.split(text.strip())
    except ValueError as exc:
        raise CommandSyntaxError(f"the command's quoting is unbalanced ({exc})") from None
    for tok in _shell_tokens(text) + tokens:
        if tok in SHELL_OPERATORS or tok.startswith(("$(", "`")):
            raise CommandSyntaxError(
                f"shell syntax like '{tok}' is not allowed: send one plain ros2 command"
            )
    if not tokens or tokens[0] != "ros2":
        raise CommandSyntaxError(f"a command must start with 'ros2', not '{tokens[0]}'")
    if len(tokens) < 3:
        raise CommandSyntaxError(f"'{' '.join(tokens)}' is incomplete; allowed: {ALLOWED}")
    if (tokens[1], tokens[2]) not in SUPPORTED:
        raise CommandSyntaxError(
            f"'ros2 {tokens[1]} {tokens[2]}' is not supported; allowed: {ALLOWED}"
        )
    return tokens


def parse(text: str, distro: str | None = None) -> Ros2Command:
    distro = distro or current_distro()
    tokens = _tokens(text)
    key = (tokens[1], tokens[2])
    try:
        ns = vars(_parser(distro).parse_args(tokens[1:]))
    except CommandSyntaxError as exc:
        example = EXAMPLES.get(key)
        message = _suggest(distro, key, str(exc))
        raise CommandSyntaxError(message + (f" (e.g. {example})" if example else "")) from None
    if ns.get("stdin"):
        raise CommandSyntaxError("astiop does not read values from stdin: give them as an argument")
    verb = VERBS[key]
    args: dict[str, Any] = {}
    for dest in ("topic_name", "service_name", "action_name"):
        if ns.get(dest):
            args["name"] = normalize_name(ns[dest])
    if key[0] == "node" and ns.get("node_name"):
        args["name"] = normalize_name(ns["node_name"])
    if key[0] == "param":
        if ns.get("node_name"):
            args["node"] = normalize_name(ns["node_name"])
        for dest, name in (("parameter_name", "param"), ("value", "value")):
            if ns.get(dest) is not None:
                args[name] = ns[dest]
    for dest in ("message_type", "service_type", "action_type", "type"):
        if ns.get(dest):
            args["type"] = ns[dest]
    if verb.values_from:
        args["values"] = parse_values(ns.get(verb.values_from) or "")
    option_names = {**_OPTIONS, **verb.options}
    flags = frozenset(ours for dest, ours in _FLAGS.items() if ns.get(dest))
    options = {ours: ns[dest] for dest, ours in option_names.items() if ns.get(dest) is not None}
    if verb.normalize is not None:
        verb.normalize(ns, options)
    return Ros2Command(
        text.strip(), key[0], key[1], args, flags, options, tuple(tokens[1:]), distro
    )


def _shell_tokens(text: str) -> list[str]:
    """Unquoted shell operators as tokens of their own (`/scan;` -> `/scan`, `;`)."""
    lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    try:
        return list(lexer)
    except ValueError:
        return []
