"""Parsed ROS 2 interface types: `interface show`, default values, and checking YAML values."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import cache
from typing import Any

from astiop.bounded import preview
from astiop.distro import current_distro
from astiop.ros2.definitions import DEFINITIONS, definitions

INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "byte": (0, 255),
    "char": (0, 255),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
FLOATS = {"float32", "float64"}
PRIMITIVES = set(INT_RANGES) | FLOATS | {"bool", "string", "wstring"}
_FIELD = re.compile(
    r"^(?P<type>[\w/]+)(?P<array>\[(?P<size><=)?(?P<n>\d*)\])?\s+(?P<name>\w+)"
    r"(?:\s*=\s*(?P<const>.+)|\s+(?P<default>.+))?$"
)


class InterfaceError(ValueError):
    """A value does not fit its ROS 2 type; the message says which field and why."""


@dataclass(frozen=True)
class Field:
    name: str
    type: str  # primitive or full 'pkg/msg/Name'
    is_array: bool = False
    array_size: int | None = None  # fixed size, or bound when `bounded`
    bounded: bool = False
    default: Any = None


@dataclass(frozen=True)
class MessageType:
    name: str
    fields: tuple[Field, ...]
    constants: tuple[tuple[str, str, str], ...] = ()

    def field(self, name: str) -> Field | None:
        return next((f for f in self.fields if f.name == name), None)


def normalize_type(name: str) -> str:
    """`geometry_msgs/Twist` -> `geometry_msgs/msg/Twist`, as the ros2 CLI accepts."""
    parts = name.strip().split("/")
    if len(parts) == 2:
        pkg, base = parts
        for kind in ("msg", "srv", "action"):
            if f"{pkg}/{kind}/{base}" in DEFINITIONS:
                return f"{pkg}/{kind}/{base}"
        return f"{pkg}/msg/{base}"
    return name.strip()


def known_type(name: str) -> bool:
    return normalize_type(name) in DEFINITIONS


def _resolve(type_token: str, package: str) -> str:
    if type_token in PRIMITIVES:
        return type_token
    if type_token == "Header":
        return "std_msgs/msg/Header"
    if "/" in type_token:
        return normalize_type(type_token)
    return f"{package}/msg/{type_token}"


def _parse_block(name: str, text: str) -> MessageType:
    package = name.split("/")[0]
    fields, constants = [], []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = _FIELD.match(line)
        if not m:
            raise ValueError(f"bad definition line in {name}: {raw!r}")
        ftype = _resolve(m["type"], package)
        if m["const"] is not None:
            constants.append((m["type"], m["name"], m["const"].strip()))
            continue
        n = int(m["n"]) if m["array"] and m["n"] else None
        default = None
        if m["default"] is not None and ftype in FLOATS:
            default = float(m["default"])
        fields.append(Field(m["name"], ftype, bool(m["array"]), n, bool(m["size"]), default))
    return MessageType(name, tuple(fields), tuple(constants))


def _distro(distro: str | None) -> str:
    if distro is None:
        return current_distro()
    return distro


def get_parts(type_name: str, distro: str | None = None) -> tuple[MessageType, ...]:
    """A message: one part; a service: request, response; an action: goal, result, feedback;
    as the robot's distro (ROS_DISTRO, default jazzy) defines it."""
    return _parts(type_name, _distro(distro))


@cache
def _parts(type_name: str, distro: str) -> tuple[MessageType, ...]:
    name = normalize_type(type_name)
    defs = definitions(distro)
    if name not in defs:
        raise InterfaceError(f"unknown interface type '{type_name}'")
    blocks = re.split(r"^---\s*$", defs[name], flags=re.M)
    suffixes = {1: [""], 2: ["_Request", "_Response"], 3: ["_Goal", "_Result", "_Feedback"]}
    return tuple(_parse_block(name + sfx, blk) for sfx, blk in zip(suffixes[len(blocks)], blocks))


def used_types(type_name: str, distro: str | None = None) -> list[str]:
    """Every type `type_name` uses, directly or not, first use first (for ros2msg schemas)."""
    root = normalize_type(type_name)
    seen, queue, order = {root}, [root], []
    while queue:
        name = queue.pop(0)
        package = name.split("/")[0]
        for part in get_parts(name, distro):
            for f in part.fields:
                dep = _resolve(f.type, package)
                if dep not in PRIMITIVES and dep not in seen:
                    seen.add(dep)
                    queue.append(dep)
                    order.append(dep)
    return order


# -- `ros2 interface show` --------------------------------------------------------------
def interface_show(type_name: str, distro: str | None = None) -> str:
    name = normalize_type(type_name)
    defs = definitions(_distro(distro))
    if name not in defs:
        raise InterfaceError(f"unknown interface type '{type_name}'")
    lines: list[str] = []
    for raw in defs[name].rstrip("\n").splitlines():
        lines.append(raw)
        _expand(raw, name.split("/")[0], 1, lines, defs)
    return "\n".join(lines) + "\n"


def _expand(raw: str, package: str, depth: int, out: list[str], defs: dict[str, str]) -> None:
    line = raw.split("#", 1)[0].strip()
    m = _FIELD.match(line) if line and line != "---" else None
    if not m or m["const"] is not None:
        return
    ftype = _resolve(m["type"], package)
    if ftype in PRIMITIVES:
        return
    for sub in defs[ftype].rstrip("\n").splitlines():
        if not sub.strip() or sub.lstrip().startswith("#"):
            continue
        out.append("\t" * depth + sub)
        _expand(sub, ftype.split("/")[0], depth + 1, out, defs)


# -- defaults and checking -----------------------------------------------------------
def _zero(f: Field) -> Any:
    if f.type in FLOATS:
        return f.default if f.default is not None else 0.0
    if f.type in INT_RANGES:
        return 0
    if f.type == "bool":
        return False
    if f.type in ("string", "wstring"):
        return ""
    return default_value(f.type)


def default_value(type_name: str, part: int = 0) -> dict[str, Any]:
    mt = get_parts(type_name)[part]
    out: dict[str, Any] = {}
    for f in mt.fields:
        if f.is_array:
            out[f.name] = [_zero(f) for _ in range(f.array_size or 0)] if not f.bounded else []
        else:
            out[f.name] = _zero(f)
    return out


FLOAT32_MAX = 3.4028234663852886e38


def _check_scalar(f: Field, value: Any, where: str) -> Any:
    t = f.type
    shown = preview(repr(value), 40)
    if t in FLOATS:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InterfaceError(f"field '{where}' must be a number ({t}), got {shown}")
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number) or (t == "float32" and abs(number) > FLOAT32_MAX):
            raise InterfaceError(f"field '{where}' must be a finite {t}, got {shown}")
        return number
    if t in INT_RANGES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise InterfaceError(f"field '{where}' must be an integer ({t}), got {shown}")
        lo, hi = INT_RANGES[t]
        if not lo <= value <= hi:
            raise InterfaceError(f"field '{where}' must be within {lo}..{hi} ({t}), got {shown}")
        return value
    if t == "bool":
        if not isinstance(value, bool):
            raise InterfaceError(f"field '{where}' must be true or false, got {shown}")
        return value
    if t in ("string", "wstring"):
        if not isinstance(value, (str, int, float)) or isinstance(value, bool):
            raise InterfaceError(f"field '{where}' must be a string, got {shown}")
        return str(value)
    if not isinstance(value, dict):
        raise InterfaceError(
            f"field '{where}' is a {t} and takes a mapping like {{...}}, got {shown}"
        )
    return fill(t, value, where=where)


def fill(type_name: str, values: dict[str, Any] | None, part: int = 0, where: str = "") -> dict:
    """Check `values` against the type and return a complete message with defaults filled in."""
    mt = get_parts(type_name)[part]
    values = values or {}
    if not isinstance(values, dict):
        raise InterfaceError(f"{mt.name} takes a mapping of its fields, got {values!r}")
    known = {f.name for f in mt.fields}
    for key in values:
        if key not in known:
            listed = ", ".join(sorted(known)) or "none"
            raise InterfaceError(f"{mt.name} has no field '{key}' (fields: {listed})")
    out = default_value(type_name, part)
    for f in mt.fields:
        if f.name not in values:
            continue
        where_f = f"{where}.{f.name}" if where else f.name
        value = values[f.name]
        if f.is_array:
            if not isinstance(value, list):
                raise InterfaceError(f"field '{where_f}' must be a list, got {value!r}")
            if f.array_size is not None and not f.bounded and len(value) != f.array_size:
                raise InterfaceError(f"field '{where_f}' must have exactly {f.array_size} items")
            out[f.name] = [_check_scalar(f, v, f"{where_f}[{i}]") for i, v in enumerate(value)]
        else:
            out[f.name] = _check_scalar(f, value, where_f)
    return out


def python_repr(type_name: str, value: dict[str, Any], part: int = 0) -> str:
    """How rclpy prints a message: `std_srvs.srv.Trigger_Response(success=True, message='')`."""
    mt = get_parts(type_name)[part]
    dotted = mt.name.replace("/", ".")
    items = []
    for f in mt.fields:
        v = value.get(f.name)
        if isinstance(v, dict) and f.type not in PRIMITIVES:
            items.append(f"{f.name}={python_repr(f.type, v)}")
        elif f.is_array and f.type not in PRIMITIVES and isinstance(v, list):
            items.append(f"{f.name}=[{', '.join(python_repr(f.type, item) for item in v)}]")
        else:
            items.append(f"{f.name}={v!r}")
    return f"{dotted}({', '.join(items)})"


# -- reading what `ros2 topic echo` printed ------------------------------------------------
def decode_bytes(type_name: str, value: Any, part: int = 0) -> Any:
    """`byte` and `char` fields print as one-character strings ("\\x02"); give back numbers."""
    try:
        mt = get_parts(type_name)[part]
    except InterfaceError:
        return value
    if not isinstance(value, dict):
        return value
    out = dict(value)
    for f in mt.fields:
        v = out.get(f.name)
        if v is None:
            continue
        if f.type in ("byte", "char", "uint8") and not f.is_array and isinstance(v, (str, bytes)):
            out[f.name] = v[0] if isinstance(v, bytes) else (ord(v) if len(v) == 1 else v)
        elif f.type not in PRIMITIVES:
            if f.is_array and isinstance(v, list):
                out[f.name] = [decode_bytes(f.type, item) for item in v]
            elif not f.is_array:
                out[f.name] = decode_bytes(f.type, v)
    return out
