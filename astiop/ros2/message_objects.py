"""ROS 2 message objects (the Python classes rosidl generates) to and from astiop's plain dicts.

The classes are imported by name at run time, so this module needs no ROS install until it is
used. Fields are walked through each class's `SLOT_TYPES` (rosidl_parser definitions), as
rosidl_runtime_py/convert.py and set_message.py do on humble and jazzy.
"""

from __future__ import annotations

import importlib
from functools import cache
from typing import Any


class MessageTypeError(Exception):
    """The type's package is not importable here, or the value does not fit the type."""


@cache
def interface_class(type_name: str) -> type:
    """`pkg/msg/Name`, `pkg/srv/Name` or `pkg/action/Name` as its generated class."""
    try:
        pkg, kind, name = type_name.split("/")
    except ValueError:
        raise MessageTypeError(f"'{type_name}' is not pkg/kind/Name") from None
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError):
        raise MessageTypeError(f"{type_name} is not importable here (is {pkg} built?)") from None


def _nested_class(slot: Any) -> type | None:
    namespaces = getattr(slot, "namespaces", None)
    if namespaces is None:
        return None
    return interface_class("/".join([*namespaces, slot.name]))


def _element(slot: Any) -> Any:
    return getattr(slot, "value_type", None)  # a sequence or an array: its element's type


def to_message(cls: Any, data: dict[str, Any]) -> Any:
    """A message object of `cls` with the fields given in `data` (others keep their default)."""
    msg = cls()
    slots = dict(zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES))
    for key, value in data.items():
        slot = slots.get(key)
        if slot is None:
            raise MessageTypeError(f"{cls.__name__} has no field '{key}'")
        nested = _nested_class(slot)
        if nested is not None:
            value = to_message(nested, value)
        else:
            element = _element(slot)
            element_class = _nested_class(element) if element is not None else None
            if element_class is not None:
                value = [to_message(element_class, v) for v in value]
        try:
            setattr(msg, key, value)
        except (AssertionError, TypeError, ValueError) as exc:
            raise MessageTypeError(f"{cls.__name__}.{key}: {exc}") from None
    return msg


def to_dict(msg: Any) -> dict[str, Any]:
    """A message object as a plain dict: nested messages as dicts, arrays as lists."""
    out: dict[str, Any] = plain(msg)
    return out


def plain(value: Any, *, byte_chars: bool = False) -> Any:
    """A message as the dicts and lists the rest of astiop reads, whichever made it: a class
    rosidl generated (rclpy, the emulated ros2) or one mcap-ros2-support decoded (a recording).
    Nested messages become dicts, arrays and numpy values lists and numbers, and bytes a list
    of ints or, with `byte_chars`, one string of characters (ros2cli prints a `byte` so:
    rosidl_runtime_py/convert.py `_convert_value`, humble and jazzy)."""
    fields = _field_names(value)
    if fields is not None:
        return {k: plain(getattr(value, k), byte_chars=byte_chars) for k in fields}
    if isinstance(value, (bytes, bytearray)):
        return "".join(chr(c) for c in value) if byte_chars else list(value)
    if hasattr(value, "tolist") and not isinstance(value, (int, float)):
        value = value.tolist()  # numpy arrays and scalars, array.array
    if isinstance(value, (list, tuple)):
        return [plain(v, byte_chars=byte_chars) for v in value]
    return value


def _field_names(value: Any) -> Any:
    """A message's field names, None for a value that is no message."""
    if hasattr(value, "get_fields_and_field_types"):  # rosidl's (its __slots__ are `_x`)
        return value.get_fields_and_field_types()
    slots = getattr(type(value), "__slots__", None)  # mcap-ros2-support's decoded classes
    if slots and not isinstance(value, (str, bytes)):
        return slots
    return None
