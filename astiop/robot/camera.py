"""The robot's camera as the console shows it: the camera role's latest frame, decoded to RGB
pixels, or one line saying why there is none (no camera, no frame yet, an encoding astiop
cannot read: nothing is shown rather than garbage)."""

from __future__ import annotations

import io
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from astiop.transports.images import ImageMessage

if TYPE_CHECKING:
    from astiop.robot.gateway import RobotGateway

# Image encodings read (sensor_msgs/image_encodings.hpp): channels, and the RGB order of them
RAW_ENCODINGS: dict[str, tuple[int, tuple[int, ...]]] = {
    "rgb8": (3, (0, 1, 2)),
    "bgr8": (3, (2, 1, 0)),
    "rgba8": (4, (0, 1, 2)),
    "bgra8": (4, (2, 1, 0)),
    "mono8": (1, (0, 0, 0)),
    "8uc1": (1, (0, 0, 0)),
    "8uc3": (3, (2, 1, 0)),  # OpenCV's order
}
MAX_SIDE_PX = 8192


class ImageError(ValueError):
    """A frame astiop cannot read: its reason names the encoding or the fault."""


@dataclass(frozen=True)
class CameraFrame:
    topic: str
    pixels: np.ndarray  # (height, width, 3) uint8, RGB, top row first
    encoding: str  # as the robot said it: "rgb8", "png", "jpeg"...
    at: float | None  # when it came, on the robot's clock (`RobotState.t`)

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])


@dataclass(frozen=True)
class CameraReading:
    frame: CameraFrame | None
    note: str = ""  # why there is no frame, or what is wrong with the last one
    absent: bool = False  # none will come: the robot has no camera, or this transport reads none


def decode(msg: ImageMessage) -> np.ndarray:
    """RGB pixels (height, width, 3) of a frame; ImageError when it cannot be read."""
    if msg.compressed:
        return _decompress(msg)
    w, h, enc = msg.width, msg.height, msg.encoding.lower()
    if enc not in RAW_ENCODINGS:
        raise ImageError(f"{msg.topic}: images in '{msg.encoding}' cannot be shown")
    channels, order = RAW_ENCODINGS[enc]
    if not (0 < w <= MAX_SIDE_PX and 0 < h <= MAX_SIDE_PX):
        raise ImageError(f"{msg.topic}: a {w} x {h} image cannot be shown")
    step = msg.step or w * channels
    if step < w * channels or len(msg.data) < step * h:
        raise ImageError(
            f"{msg.topic}: {len(msg.data)} bytes do not hold {h} rows of {step} ({msg.encoding})"
        )
    rows = np.frombuffer(msg.data, dtype=np.uint8, count=step * h).reshape(h, step)
    pixels = rows[:, : w * channels].reshape(h, w, channels)
    return pixels[:, :, list(order)] if order != (0, 1, 2) or channels != 3 else pixels


def _decompress(msg: ImageMessage) -> np.ndarray:
    from PIL import Image as PILImage  # a compressed frame only

    try:
        with PILImage.open(io.BytesIO(msg.data)) as img:
            if img.width > MAX_SIDE_PX or img.height > MAX_SIDE_PX:
                raise ImageError(f"{msg.topic}: a {img.width} x {img.height} image is too large")
            return np.asarray(img.convert("RGB"))
    except (OSError, SyntaxError, ValueError) as exc:
        if isinstance(exc, ImageError):
            raise
        fmt = msg.encoding or "format not said"
        raise ImageError(f"{msg.topic}: a compressed image ({fmt}) that cannot be read") from None


def fitted(width: int, height: int, max_side: int | None) -> tuple[int, int]:
    """The size a width x height picture is sent at: its longer side at most `max_side`
    (None: as it is), at its aspect."""
    longest = max(width, height)
    if max_side is None or longest <= max_side:
        return width, height
    return max(1, round(width * max_side / longest)), max(1, round(height * max_side / longest))


def png_of(frame: CameraFrame, max_side: int | None = None) -> tuple[bytes, float]:
    """The frame's pixels as PNG bytes (what a model or an MCP client is sent), scaled down to
    `fitted(..., max_side)`, and the seconds scaling and encoding took."""
    from PIL import Image as PILImage

    t0 = time.perf_counter()
    buf = io.BytesIO()
    picture = PILImage.fromarray(frame.pixels, "RGB")
    size = fitted(frame.width, frame.height, max_side)
    if size != picture.size:
        picture = picture.resize(size, PILImage.Resampling.BILINEAR, reducing_gap=2.0)
    picture.save(buf, "PNG")
    return buf.getvalue(), time.perf_counter() - t0


def age_of(frame: CameraFrame, now: float | None) -> float | None:
    """The frame's age at `now` on the robot's clock (`RobotState.t`); None when unknown."""
    return None if frame.at is None or now is None else max(0.0, now - frame.at)


def read_camera(gateway: RobotGateway) -> CameraReading:
    """The current robot's camera frame, through its camera role."""
    name = gateway.profile.name("camera")
    if name is None or gateway.profile.kind("camera") != "topic":
        return CameraReading(None, "no camera", absent=True)
    try:
        msg = gateway.backend.image(name)
    except ValueError as exc:
        return CameraReading(None, str(exc), absent=True)
    if msg is None:
        return CameraReading(None, f"no frame yet on {name}")
    try:
        return CameraReading(CameraFrame(msg.topic, decode(msg), msg.encoding, msg.at))
    except ImageError as exc:
        return CameraReading(None, str(exc))
