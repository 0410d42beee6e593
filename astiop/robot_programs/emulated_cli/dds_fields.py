"""Message objects as ros2cli reads and prints them, for the DDS-mode emulated `ros2`.

Without rosidl_runtime_py here, its two halves that ros2cli uses, as on its humble and jazzy
branches (rosidl_runtime_py/convert.py `message_to_ordereddict`/`_convert_value`, and
set_message.py `set_message_fields`): a `byte` prints as a one-character string, a value is
converted to its field's type (`x: 1` fills a double), and on Jazzy `header: auto` and
`stamp: now` are stamped at each publication.
"""

from __future__ import annotations

import array
import importlib
from collections.abc import Callable
from typing import Any

from astiop.ros2.message_objects import interface_class, plain
from astiop.ros2.printing import ros2cli_yaml


def message_to_yaml(msg: Any) -> str:
    return ros2cli_yaml(plain(msg, byte_chars=True))


def load_class(type_name: str, kind: str) -> Any:
    """rosidl_runtime_py's get_message/get_service/get_action: `pkg/kind/Name` or `pkg/Name`;
    None when it is not importable in this install."""
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3 or parts[1] != kind or not all(parts):
        return None
    try:
        return getattr(importlib.import_module(f"{parts[0]}.{kind}"), parts[2])
    except (ImportError, AttributeError, ValueError):
        return None


def _qualified(obj: Any) -> str:
    return f"{type(obj).__module__.split('.')[0]}/{type(obj).__name__}"


def set_message_fields(msg: Any, values: Any, *, expand: bool = False) -> list[Callable]:
    """Fill `msg` from a dict as set_message_fields does; with `expand` (Jazzy's pub), the
    setters of `header: auto` and `stamp: now` fields are returned, to stamp each message."""
    stamps: list[Callable] = []
    _set(msg, values, expand, stamps)
    return stamps


def _set(msg: Any, values: Any, expand: bool, stamps: list[Callable]) -> None:
    try:
        items = values.items()
    except AttributeError:
        raise TypeError(f'Value "{values}" is of type "{type(values)}", expected a dict') from None
    slots = dict(zip(msg.get_fields_and_field_types(), msg.SLOT_TYPES))
    for name, given in items:
        field = getattr(msg, name)  # AttributeError for a field the type lacks, as rosidl
        kind = type(field)
        if kind is array.array:
            value = array.array(field.typecode, given)
        elif kind.__name__ == "ndarray":
            import numpy

            value = numpy.array(given, dtype=field.dtype)
        elif type(given) is kind:
            value = given
        elif expand and _qualified(field) == "std_msgs/Header" and given == "auto":
            stamps.append(lambda now, h=field: setattr(h, "stamp", now))
            continue
        elif expand and _qualified(field) == "builtin_interfaces/Time" and given == "now":
            stamps.append(lambda now, m=msg, n=name: setattr(m, n, now))
            continue
        else:
            try:
                value = kind(given)
            except TypeError:
                value = kind()
                _set(value, given, expand, stamps)
        element = getattr(slots[name], "value_type", None)
        if element is not None and getattr(element, "namespaces", None):
            cls = interface_class("/".join([*element.namespaces, element.name]))
            items_ = []
            for item in value:
                sub = cls()
                _set(sub, item, expand, stamps)
                items_.append(sub)
            value = items_
        setattr(msg, name, value)
