"""Text as the `ros2` CLI prints it: echo YAML and indented values."""

from __future__ import annotations

import math
import re
from typing import Any

import yaml

TRUNCATE = 128
# libyaml's emitter when PyYAML has it: the same text, several times faster (a /scan at 10 Hz)
DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def _prepare(value: Any, no_arr: bool, truncate: int | None, no_str: bool = False) -> Any:
    # as rosidl_runtime_py/convert.py `_convert_value` does it (humble and jazzy): strings and
    # sequences cut at the truncate length with '...', --no-str shows only a string's length
    if isinstance(value, dict):
        return {k: _prepare(v, no_arr, truncate, no_str) for k, v in value.items()}
    if isinstance(value, bytes | bytearray):  # uint8[] kept as bytes (the simulator's pixels)
        value = list(value)  # as rclpy's message reads: a list of ints
    if isinstance(value, str):
        if no_str:
            return f"<string length: <{len(value)}>>"
        if truncate is not None and len(value) > truncate:
            return value[:truncate] + "..."
        return value
    if isinstance(value, list):
        if no_arr and value and not isinstance(value[0], dict):
            kind = "double" if isinstance(value[0], float) else type(value[0]).__name__
            return f"<sequence type: {kind}, length: {len(value)}>"
        cut = len(value) if truncate is None else truncate
        items = [_prepare(v, no_arr, truncate, no_str) for v in value[:cut]]
        return items + ["..."] if len(value) > cut else items
    if isinstance(value, float) and math.isnan(value):
        return float("nan")
    return value


def echo_yaml(
    message: dict[str, Any],
    no_arr: bool = False,
    truncate: int | None = TRUNCATE,
    no_str: bool = False,
) -> str:
    """As `ros2 topic echo` prints one message; `truncate=None` is its --full-length."""
    body = yaml.dump(
        _prepare(message, no_arr, truncate, no_str),
        Dumper=DUMPER,
        sort_keys=False,
        default_flow_style=False,
        width=1000,
    )
    return body + "---\n"


def echo_text(message: dict[str, Any], command: Any) -> str:
    """The operator's text for an echo, with the options they typed: -l/--truncate-length,
    -f/--full-length, --no-arr, --no-str."""
    flags = command.flags
    truncate = None if "full_length" in flags else command.options.get("truncate", TRUNCATE)
    return echo_yaml(message, "no_arr" in flags, truncate, "no_str" in flags)


def indent_yaml(message: dict[str, Any], spaces: int = 4) -> str:
    text = yaml.dump(message, Dumper=DUMPER, sort_keys=False, default_flow_style=False, width=1000)
    pad = " " * spaces
    return "".join(pad + line + "\n" for line in text.splitlines())


def ros2cli_yaml(values: Any) -> str:
    """As rosidl_runtime_py's message_to_yaml prints a message or a field: block style, whole
    length (send_goal's goal and result, echo --field)."""
    return yaml.dump(
        _prepare(values, False, None),
        Dumper=DUMPER,
        sort_keys=False,
        default_flow_style=False,
        allow_unicode=True,
        width=2**31 - 1,  # rosidl passes sys.maxsize; libyaml takes a C int
    )


def node_info_text(node: str, sections: dict[str, list[tuple[str, str]]]) -> str:
    """As `ros2 node info` prints a node: each section, then its name: type lines."""
    lines = [node]
    for section, items in sections.items():
        lines.append(f"  {section}:")
        lines += [f"    {n}: {t}" for n, t in items]
    return "\n".join(lines) + "\n"


COUNTS = ("count_topics", "count_services", "count_actions")


def list_text(pairs: list[tuple[str, str]], flags) -> tuple[str, list[str]]:
    """`ros2 topic|service|action list` as ros2cli prints it (`-t` the types, `-c` the count,
    nothing for an empty graph: ros2topic/verb/list.py, ros2service/verb/list.py, humble and
    jazzy alike), and the names; `pairs` are (name, type) in the order to print."""
    names = [n for n, _ in pairs]
    if any(f in flags for f in COUNTS):
        return f"{len(names)}\n", names
    if "show_types" in flags:
        return "".join(f"{n} [{t}]\n" for n, t in pairs), names
    return "".join(f"{n}\n" for n in names), names


def param_list_text(
    params: list[tuple[str, str, str]], node: str | None, flags, options
) -> tuple[str, dict[str, list[str]]]:
    """`ros2 param list [NODE] [--filter RE] [--param-prefixes P ...] [--param-type]` as ros2cli
    prints it (ros2param/verb/list.py, jazzy and humble): nodes sorted, each `NODE:` line only
    when no node was named, names sorted, `  name (type: T)` with --param-type; a prefix keeps a
    name equal to it or under it (`prefix.`), as rclpy's Node.list_parameters does. `params` are
    (node, name, type); the values are each node's listed names."""
    prefixes = options.get("param_prefixes") or []
    pattern = re.compile(options["filter"]) if options.get("filter") else None
    by_node: dict[str, dict[str, str]] = {}
    for owner, name, type_ in params:
        by_node.setdefault(owner, {})[name] = type_
    lines: list[str] = []
    values: dict[str, list[str]] = {}
    for owner in sorted(by_node):
        if node and owner != node:
            continue
        names = sorted(
            n for n in by_node[owner]
            if not prefixes or any(n == p or n.startswith(p + ".") for p in prefixes)
        )  # fmt: skip
        if pattern is not None:
            names = [n for n in names if pattern.match(n)]
        if not node and names:
            lines.append(f"{owner}:")
        typed = "param_type" in flags
        lines += [f"  {n} (type: {by_node[owner][n]})" if typed else f"  {n}" for n in names]
        values[owner] = names
    return "".join(f"{line}\n" for line in lines), values


INTERFACE_KINDS = (("msg", "Messages:", "only_msgs"), ("srv", "Services:", "only_srvs"),
                   ("action", "Actions:", "only_actions"))  # fmt: skip
INTERFACE_FLAGS = tuple(flag for _kind, _heading, flag in INTERFACE_KINDS)


def interface_list_text(names: list[str], flags) -> tuple[str, list[str]]:
    """`ros2 interface list [-m] [-s] [-a]` as ros2cli prints it (ros2interface/verb/list.py,
    jazzy and humble): a heading per kind, then `    pkg/kind/Name` sorted; with -m, -s or -a
    only those kinds. `names` are full names (pkg/msg/Name); the values are those printed."""
    chosen = [k for k in INTERFACE_KINDS if k[2] in flags] or list(INTERFACE_KINDS)
    lines, shown = [], []
    for kind, heading, _flag in chosen:
        lines.append(heading)
        of_kind = sorted(n for n in names if n.split("/")[1:2] == [kind])
        lines += [f"    {n}" for n in of_kind]
        shown += of_kind
    return "".join(f"{line}\n" for line in lines), shown


def type_of(value: object) -> str:
    """A parameter's type as `ros2 param list --param-type` names it (ros2param/api
    get_parameter_type_string), from its value."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    return "string" if isinstance(value, str) else "not set"
