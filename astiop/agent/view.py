"""What the robot sees (`Subject("view")`: "what is in front of the robot?", "what does the camera
see?"). A model that takes images (`LLMEndpoint.sees`) is sent the camera's current frame as a
PNG in the request, and its answer is said as coming from that frame, with the frame's age. A
model that cannot see, or no frame to send, is said in one line, and the answer comes from the
lidar's obstacles (or its scan) instead: never a view made up."""

from __future__ import annotations

import asyncio
import base64
import math
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

from astiop.agent.models.llm import LLMError
from astiop.agent.models.specs import LLMEndpoint
from astiop.agent.result import TurnResult
from astiop.agent.roles import no_return
from astiop.agent.summaries import summarize
from astiop.bounded import one_line
from astiop.robot.camera import CameraFrame, age_of, fitted, png_of
from astiop.transports.base import Execution

Ask = Callable[..., Awaitable[Any]]  # the agent's one way to the model (`Agent._ask`)
MAX_TOKENS = 160
MAX_ANSWER_CHARS = 800
# a frame's longer side as sent: Gemma 3's image encoder takes 896 x 896, and a robot's 1080p
# frame would be ~3 MB of PNG in every request (the Waffle's upstream camera is 1920 x 1080)
MODEL_MAX_SIDE = 896
SYSTEM = (
    "You are shown one frame from the forward-facing camera of a warehouse mobile robot "
    "({width} x {height} px, taken {age}). Answer the operator's question in one or two short "
    "sentences by describing what the image shows: walls, shelves or racks, stations and their "
    "colours, other robots, people, boxes, open floor, and where in the frame (left, centre, "
    "right). Say only what you can see in the image; if it is unclear, say so. Give no "
    "distances and no other numbers."
)


@dataclass(frozen=True)
class Snapshot:
    """The frame as sent: its PNG, and how long encoding it took."""

    frame: CameraFrame
    age_s: float | None
    png: bytes
    encode_s: float

    @property
    def age(self) -> str:
        return "age unknown" if self.age_s is None else f"{self.age_s:.1f} s old"

    def data_url(self) -> str:
        return "data:image/png;base64," + base64.b64encode(self.png).decode("ascii")


def image_messages(request: str, shot: Snapshot) -> list[dict[str, Any]]:
    """The question and the frame, as OpenAI's chat completions take an image: a user message
    of content parts, the image an `image_url` part holding a data: URL."""
    f = shot.frame
    when = "at an unknown time" if shot.age_s is None else f"{shot.age_s:.1f} s ago"
    system = SYSTEM.format(width=f.width, height=f.height, age=when)
    return [
        {"role": "system", "content": system},
        {
            "role": "user",
            "content": [
                {"type": "text", "text": request},
                {"type": "image_url", "image_url": {"url": shot.data_url()}},
            ],
        },
    ]


async def answer(
    request: str, reads: Any, endpoint: LLMEndpoint, ask: Ask, result: TurnResult, emit
) -> str:
    """The view asked about: from the camera's frame by a seeing model, else from the lidar.
    `reads` (`subject_answers.Reads`) keeps every read as a command of the turn."""
    if not endpoint.sees:
        return "This model cannot see images; " + await _from_lidar(reads)
    shot, why = await _snapshot(reads)
    if shot is None:
        return f"No camera frame to look at ({why}); " + await _from_lidar(reads)
    emit("status", f"showing the model the camera frame ({len(shot.png)} bytes of PNG)")
    try:
        c = await ask(
            image_messages(request, shot), None, result, lambda *_: None, "answer_token",
            max_tokens=MAX_TOKENS,
        )  # fmt: skip
        text = one_line(c.text, MAX_ANSWER_CHARS)
    except LLMError as exc:
        return f"The model could not look at the camera frame ({exc}); " + await _from_lidar(reads)
    if not text:
        return "The model said nothing of the camera frame; " + await _from_lidar(reads)
    result.model_answer = text
    f = shot.frame
    return f"From the camera frame {shot.age} ({f.topic}, {f.width} x {f.height} px): {text}"


async def _snapshot(reads: Any) -> tuple[Snapshot | None, str]:
    def take() -> tuple[Snapshot | None, str]:
        gateway = reads.gateway
        reading = gateway.camera()
        frame = reading.frame
        if frame is None:
            return None, reading.note
        png, encode_s = png_of(frame, MODEL_MAX_SIDE)
        shot = Snapshot(frame, age_of(frame, gateway.state().t), png, encode_s)
        reads.ran.append(_frame_read(shot))
        return shot, ""

    return await asyncio.to_thread(take)


def _frame_read(shot: Snapshot) -> Execution:
    """The frame sent, kept as the turn's read of the camera topic."""
    f = shot.frame
    w, h = fitted(f.width, f.height, MODEL_MAX_SIDE)
    values = {"width": f.width, "height": f.height, "encoding": f.encoding, "sent_width": w,
              "sent_height": h, "png_bytes": len(shot.png),
              "encode_ms": round(shot.encode_s * 1000, 2)}  # fmt: skip
    scaled = "" if (w, h) == (f.width, f.height) else f" scaled to {w} x {h}"
    said = (
        f"camera frame {f.width} x {f.height} px ({f.encoding}), sent{scaled} as "
        f"{len(shot.png)} bytes of PNG"
    )
    return Execution(
        f"ros2 topic echo {f.topic} --once", True, kind="read", executed=True, output=said,
        values=values, provenance="measured", age_s=shot.age_s, role="camera",
    )  # fmt: skip


FRONT_DEG = 30.0  # "in front": within this of straight ahead (about a camera's half-width)


async def _from_lidar(reads: Any) -> str:
    """What the lidar reports in front of the robot: its scan's nearest return ahead, and its
    obstacles ahead (each role the robot has, read once)."""
    profile = reads.gateway.profile
    said = []
    for role in ("scan", "obstacles"):
        name = profile.name(role)
        if not name:
            continue
        ex = await asyncio.to_thread(reads.run, f"ros2 topic echo {name} --once")
        if not ex.executed or ex.error:
            said.append(f"its {name} could not be read ({one_line(ex.error or ex.reason, 120)})")
            continue
        age = "age unknown" if ex.age_s is None else f"{ex.age_s:.1f} s old"
        ahead = in_front(role, ex.values or {})
        said.append(f"{name} ({age}): {ahead or summarize(ex).split(chr(10), 1)[-1].strip()}")
    if not said:
        return "the robot has no lidar reading either, so I cannot say what is in front of it."
    return "from the lidar, " + "; ".join(said) + "."


def _ahead(bearing_rad: float) -> float | None:
    """The bearing in degrees (-180..180], when it is in front; None otherwise."""
    deg = math.degrees(math.atan2(math.sin(bearing_rad), math.cos(bearing_rad)))
    return deg if abs(deg) <= FRONT_DEG else None


def in_front(role: str, v: dict) -> str | None:
    """What a scan or an obstacle list says of the sector ahead; None if it is neither."""
    if role == "scan" and "ranges" in v:
        hits = [
            (r, bearing)
            for i, r in enumerate(v["ranges"])
            if not no_return(r, v)
            and (bearing := _ahead(v["angle_min"] + i * v["angle_increment"])) is not None
        ]
        if not hits:
            return f"no return within {FRONT_DEG:.0f} deg of straight ahead"
        r, bearing = min(hits)
        return (
            f"the nearest return within {FRONT_DEG:.0f} deg of straight ahead is {r:.2f} m, "
            f"at {bearing:+.0f} deg"
        )
    if role == "obstacles" and "obstacles" in v:
        ahead = [o for o in v["obstacles"] if _ahead(o["bearing"]) is not None]
        elsewhere = len(v["obstacles"]) - len(ahead)
        rest = f" ({elsewhere} elsewhere)" if elsewhere else ""
        if not ahead:
            return f"no obstacle ahead{rest}"
        items = ", ".join(f"{o['kind']} at {o['distance']:.1f} m" for o in ahead[:5])
        return f"{len(ahead)} obstacle(s) ahead: {items}{rest}"
    return None
