"""ROS 2 message objects (the Python classes rosidl generates) to and from astiop's plain dicts.

The classes are imported by name at run time, so this module needs no ROS install until it is
used. Fields are walked through each class's `SLOT_TYPES` (rosidl_parser definitions), as
rosidl_runtime_py/convert.py and set_message.py do on humble and jazzy.
"""

from __future__ import annotations

import array
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
    out: dict[str, Any] = {}
    for key in msg.get_fields_and_field_types():
        out[key] = _plain(getattr(msg, key))
    return out


def _plain(value: Any) -> Any:
    if hasattr(value, "get_fields_and_field_types"):
        return to_dict(value)
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, array.array):
        return value.tolist()
    if isinstance(value, bytes):
        return list(value)
    if hasattr(value, "tolist"):  # a fixed-size array comes as numpy
        return value.tolist()
    return value
