"""The subset of the `ros2` CLI the agent may use, parsed with the real CLI's syntax.

Anything outside this grammar is refused with a sentence an LLM can use to repair it; there is
no path by which other text runs.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field
from typing import Any

import yaml

SHELL_OPERATORS = {"|", "||", "&", "&&", ";", ";;", ">", ">>", "<", "<<", "$(", "`", "(", ")"}


class CommandSyntaxError(ValueError):
    """The text is not a command of the supported `ros2` subset."""


@dataclass(frozen=True)
class _Spec:
    positional: tuple[str, ...]  # names; a trailing '?' marks an optional one
    flags: dict[str, str] = field(default_factory=dict)  # option -> canonical flag
    options: dict[str, tuple[str, type]] = field(default_factory=dict)  # option -> (name, type)
    example: str = ""


_T = {"-t": "show_types", "--show-types": "show_types"}
SPECS: dict[tuple[str, str], _Spec] = {
    ("topic", "list"): _Spec((), _T, example="ros2 topic list -t"),
    ("topic", "info"): _Spec(
        ("name",), {"-v": "verbose", "--verbose": "verbose"}, example="ros2 topic info /scan"
    ),
    ("topic", "type"): _Spec(("name",), example="ros2 topic type /odom"),
    ("topic", "echo"): _Spec(
        ("name", "type?"),
        {"--once": "once", "-1": "once", "--no-arr": "no_arr"},
        {"--timeout": ("timeout", float)},
        example="ros2 topic echo /battery_status --once",
    ),
    ("topic", "hz"): _Spec(
        ("name",),
        options={"-w": ("window", int), "--window": ("window", int)},
        example="ros2 topic hz /scan",
    ),
    ("topic", "pub"): _Spec(
        ("name", "type", "values?"),
        {"--once": "once", "-1": "once"},
        {
            "-r": ("rate", float),
            "--rate": ("rate", float),
            "-t": ("times", int),
            "--times": ("times", int),
            "-p": ("print", int),
            "--print": ("print", int),
            "-w": ("wait", int),
            "--wait-matching-subscriptions": ("wait", int),
        },
        example='ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist "{linear: {x: 0.2}}"',
    ),
    ("service", "list"): _Spec((), _T, example="ros2 service list -t"),
    ("service", "type"): _Spec(("name",), example="ros2 service type /goto_position"),
    ("service", "call"): _Spec(
        ("name", "type?", "values?"),
        example="ros2 service call /goto_position astiop_msgs/srv/GotoPosition "
        "\"{name: 'shipping'}\"",
    ),
    ("action", "list"): _Spec((), _T, example="ros2 action list -t"),
    ("action", "info"): _Spec(("name",), example="ros2 action info /navigate_to_pose"),
    ("action", "send_goal"): _Spec(
        ("name", "type", "values"),
        {"-f": "feedback", "--feedback": "feedback"},
        example="ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        '"{pose: {pose: {position: {x: 5.0, y: 3.0}}}}" --feedback',
    ),
    ("node", "list"): _Spec((), example="ros2 node list"),
    ("node", "info"): _Spec(("name",), example="ros2 node info /navigator"),
    ("interface", "show"): _Spec(
        ("type",), example="ros2 interface show sensor_msgs/msg/LaserScan"
    ),
    ("interface", "list"): _Spec((), example="ros2 interface list"),
    ("param", "list"): _Spec(("node?",), example="ros2 param list /astibot_base"),
    ("param", "get"): _Spec(
        ("node", "param"), example="ros2 param get /astibot_base max_linear_speed"
    ),
    ("param", "set"): _Spec(
        ("node", "param", "value"), example="ros2 param set /astibot_base max_linear_speed 0.5"
    ),
}
ALLOWED = ", ".join(sorted({f"{v} {s}" for v, s in SPECS}))


@dataclass(frozen=True)
class Ros2Command:
    text: str
    verb: str
    sub: str
    args: dict[str, Any]  # positional values by name; 'values' holds parsed YAML
    flags: frozenset[str]
    options: dict[str, Any]
    argv: tuple[str, ...]  # what follows `ros2`, for the real CLI

    @property
    def key(self) -> tuple[str, str]:
        return (self.verb, self.sub)

    @property
    def name(self) -> str | None:
        return self.args.get("name")

    def display(self) -> str:
        return "ros2 " + shlex.join(self.argv)


def normalize_name(name: str) -> str:
    name = name.strip()
    return name if name.startswith("/") else "/" + name


def _looks_like_type(token: str) -> bool:
    return "/" in token and not token.startswith("/") and not any(c in token for c in "{}:[ ")


def parse_values(text: str) -> dict[str, Any]:
    try:
        value = yaml.safe_load(text) if text.strip() else {}
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise CommandSyntaxError(
            f"the values {text!r} are not valid YAML ({mark}); write them as a YAML mapping, "
            'e.g. "{linear: {x: 0.2}}"'
        ) from None
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise CommandSyntaxError(f'the values {text!r} must be a YAML mapping like "{{x: 1.0}}"')
    return value


def parse(text: str) -> Ros2Command:
    if not isinstance(text, str) or not text.strip():
        raise CommandSyntaxError("the command is empty; send one ros2 command")
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
    verb, sub = tokens[1], tokens[2]
    spec = SPECS.get((verb, sub))
    if spec is None:
        raise CommandSyntaxError(f"'ros2 {verb} {sub}' is not supported; allowed: {ALLOWED}")
    flags: set[str] = set()
    options: dict[str, Any] = {}
    positional: list[str] = []
    rest = tokens[3:]
    i = 0
    while i < len(rest):
        tok = rest[i]
        if tok in spec.flags:
            flags.add(spec.flags[tok])
        elif tok in spec.options:
            name, kind = spec.options[tok]
            if i + 1 >= len(rest):
                raise CommandSyntaxError(f"option {tok} of 'ros2 {verb} {sub}' needs a value")
            try:
                options[name] = kind(rest[i + 1])
            except ValueError:
                raise CommandSyntaxError(
                    f"option {tok} needs a {kind.__name__}, got '{rest[i + 1]}'"
                ) from None
            i += 1
        elif tok.startswith("-") and len(tok) > 1 and not _is_number(tok):
            allowed = ", ".join(list(spec.flags) + list(spec.options)) or "none"
            raise CommandSyntaxError(
                f"unknown option '{tok}' for 'ros2 {verb} {sub}' (allowed: {allowed})"
            )
        else:
            positional.append(tok)
        i += 1
    args = _bind(verb, sub, spec, positional)
    return Ros2Command(text.strip(), verb, sub, args, frozenset(flags), options, tuple(tokens[1:]))


def _shell_tokens(text: str) -> list[str]:
    """Unquoted shell operators as tokens of their own (`/scan;` -> `/scan`, `;`)."""
    lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    try:
        return list(lexer)
    except ValueError:
        return []


def _is_number(tok: str) -> bool:
    try:
        float(tok)
        return True
    except ValueError:
        return False


def _bind(verb: str, sub: str, spec: _Spec, positional: list[str]) -> dict[str, Any]:
    names = [p.rstrip("?") for p in spec.positional]
    required = [p for p in spec.positional if not p.endswith("?")]
    usage = f"usage: {spec.example}"
    if len(positional) < len(required):
        raise CommandSyntaxError(
            f"'ros2 {verb} {sub}' needs {', '.join(n.rstrip('?') for n in required)}; {usage}"
        )
    if len(positional) > len(names):
        raise CommandSyntaxError(
            f"too many arguments for 'ros2 {verb} {sub}' ({' '.join(positional)}); quote YAML "
            f"values as one argument; {usage}"
        )
    args: dict[str, Any] = {}
    if (
        (verb, sub) == ("service", "call")
        and len(positional) == 2
        and not _looks_like_type(positional[1])
    ):
        positional = [positional[0], "", positional[1]]  # the optional type was left out
    for name, value in zip(names, positional):
        if name == "values":
            args["values"] = parse_values(value)
        elif name in ("name",) and verb in ("topic", "service", "action", "node"):
            args["name"] = normalize_name(value)
        elif name == "node":
            args["node"] = normalize_name(value)
        elif value != "":
            args[name] = value
    return args
