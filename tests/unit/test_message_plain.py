"""One conversion of a message to plain dicts and lists for the three readers of messages: the
rclpy transport (rosidl's classes), the emulated ros2 (the same, bytes printed as ros2cli prints
them) and a recording (mcap-ros2-support's decoded classes)."""

from __future__ import annotations

import array

import numpy as np
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory

from astiop.ros2.message_objects import plain, to_dict


class Vector3:  # as rosidl generates it: underscored slots, fields named by the class
    __slots__ = ["_x", "_y", "_z"]

    def __init__(self, x=0.0, y=0.0, z=0.0):
        self._x, self._y, self._z = x, y, z

    x = property(lambda self: self._x)
    y = property(lambda self: self._y)
    z = property(lambda self: self._z)

    @classmethod
    def get_fields_and_field_types(cls):
        return {"x": "double", "y": "double", "z": "double"}


class Sample:
    __slots__ = ["_linear", "_data", "_flag", "_grid", "_ranges"]

    def __init__(self):
        self._linear = Vector3(1.0, 2.0, 3.0)
        self._data = array.array("f", [0.5, 1.5])  # a sequence<float>
        self._flag = b"\x05"  # a byte
        self._grid = np.array([1, 2, 3], dtype=np.uint8)  # a fixed-size array
        self._ranges = [Vector3(), Vector3(z=1.0)]

    linear = property(lambda self: self._linear)
    data = property(lambda self: self._data)
    flag = property(lambda self: self._flag)
    grid = property(lambda self: self._grid)
    ranges = property(lambda self: self._ranges)

    @classmethod
    def get_fields_and_field_types(cls):
        return {"linear": "", "data": "", "flag": "", "grid": "", "ranges": ""}


def test_a_rosidl_message_becomes_dicts_lists_and_numbers():
    assert to_dict(Sample()) == {
        "linear": {"x": 1.0, "y": 2.0, "z": 3.0},
        "data": [0.5, 1.5],
        "flag": [5],
        "grid": [1, 2, 3],
        "ranges": [{"x": 0.0, "y": 0.0, "z": 0.0}, {"x": 0.0, "y": 0.0, "z": 1.0}],
    }
    assert plain(Sample(), byte_chars=True)["flag"] == "\x05"  # as ros2cli prints a byte
    assert type(plain(np.float32(0.5))) is float  # a numpy scalar is a plain number


def test_a_message_mcap_ros2_decoded_becomes_the_same_dicts():
    schema = "geometry_msgs/Vector3 linear\nuint8[] data\n" + "=" * 80 + "\n"
    schema += "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
    schema_record = Schema(
        id=1, name="astiop_test/msg/Sample", encoding="ros2msg", data=schema.encode()
    )
    decode = DecoderFactory().decoder_for("cdr", schema_record)  # as a recording is read
    # CDR little-endian: header, three doubles, then a sequence of 2 bytes
    raw = bytes([0, 1, 0, 0]) + np.array([1.0, 2.0, 3.0], "<f8").tobytes()
    raw += (2).to_bytes(4, "little") + bytes([7, 9])
    assert plain(decode(raw)) == {"linear": {"x": 1.0, "y": 2.0, "z": 3.0}, "data": [7, 9]}
