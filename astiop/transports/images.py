"""An image topic's latest message as every transport hands it up: its pixels as bytes, never a
list of ints (a 640 x 480 frame is 921,600 of them), and when it came."""

from __future__ import annotations

import array
from dataclasses import dataclass
from typing import Any

MAX_IMAGE_BYTES = 32 * 1024 * 1024  # a frame larger than this is not read (a 4K rgb8 is 25 MB)


@dataclass(frozen=True)
class ImageMessage:
    topic: str
    compressed: bool  # sensor_msgs/msg/CompressedImage, else sensor_msgs/msg/Image
    width: int  # 0 for a compressed image: its data says
    height: int
    encoding: str  # Image's encoding, or CompressedImage's format ("jpeg", "png", ...)
    step: int
    is_bigendian: bool
    data: bytes
    at: float | None  # when it came, on the robot's clock (as `message_times`)


def _bytes(data: Any) -> bytes:
    if isinstance(data, bytes | bytearray | memoryview):
        return bytes(data)
    if isinstance(data, array.array):
        return data.tobytes()
    if hasattr(data, "tobytes"):  # numpy
        return data.tobytes()
    return bytes(data or [])  # a list of ints (a recording's, a CLI's echo)


def _field(msg: Any, key: str, default: Any) -> Any:
    if isinstance(msg, dict):
        return msg.get(key, default)
    return getattr(msg, key, default)


def image_message(topic: str, msg: Any, at: float | None) -> ImageMessage:
    """From a message object or its dict; ValueError when it is no image or too large."""
    data = _field(msg, "data", None)
    if data is None:
        raise ValueError(f"{topic} carries no image data")
    if len(data) > MAX_IMAGE_BYTES:
        raise ValueError(f"{topic}'s frame is {len(data)} bytes, over {MAX_IMAGE_BYTES}")
    compressed = _field(msg, "format", None) is not None
    return ImageMessage(
        topic,
        compressed,
        int(_field(msg, "width", 0)),
        int(_field(msg, "height", 0)),
        str(_field(msg, "format" if compressed else "encoding", "")),
        int(_field(msg, "step", 0)),
        bool(_field(msg, "is_bigendian", 0)),
        _bytes(data),
        at,
    )
