"""The size of a message serialized as DDS sends it (XCDR1, little endian, the 4-byte
encapsulation header first): what `ros2 topic bw` counts, for a robot that hands astiop values
rather than bytes (the simulator in process)."""

from __future__ import annotations

from typing import Any

from astiop.ros2.interfaces import get_parts

HEADER = 4
MIN_PAYLOAD = 4  # Fast DDS pads a shorter payload (std_msgs Bool, Empty: 8 bytes on the wire)
WIDTH = {
    "bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1,
    "int16": 2, "uint16": 2,
    "int32": 4, "uint32": 4, "float32": 4,
    "int64": 8, "uint64": 8, "float64": 8,
}  # fmt: skip


def serialized_size(type_name: str, values: dict[str, Any], part: int = 0) -> int:
    """Bytes on the wire, header included, of `values` as `type_name` (missing fields count at
    their zero)."""
    return HEADER + max(MIN_PAYLOAD, _struct(type_name, values, part, 0))


def _align(offset: int, width: int) -> int:
    return offset + (-offset) % width


def _struct(type_name: str, values: dict[str, Any], part: int, offset: int) -> int:
    start = offset
    fields = get_parts(type_name)[part].fields
    if not fields:
        return 1  # an empty message carries one byte (rosidl's structure_needs_at_least_one_member)
    for f in fields:
        value = values.get(f.name) if isinstance(values, dict) else None
        if f.is_array and not (f.array_size and not f.bounded):
            items = list(value or ())
            offset = _align(offset, 4) + 4  # a sequence's length
        elif f.is_array:  # a fixed array: exactly its size
            size = f.array_size or 0
            items = (list(value or ()) + [None] * size)[:size]
        else:
            items = [value]
        for item in items:
            offset = _one(f.type, item, offset)
    return offset - start


def _one(type_: str, value: Any, offset: int) -> int:
    if type_ in WIDTH:
        return _align(offset, WIDTH[type_]) + WIDTH[type_]
    if type_ == "string":
        return _align(offset, 4) + 4 + len(str(value or "").encode()) + 1
    if type_ == "wstring":
        return _align(offset, 4) + 4 + 4 * len(str(value or ""))
    return offset + _struct(type_, value or {}, 0, offset)
