"""The current robot's camera: its latest frame as half-block cells (▀, the upper pixel the
foreground, the lower the background: two pixels a cell, in any terminal and in the browser),
or as real pixels where the terminal draws images (`camera_pixels`), with its topic, size,
encoding and age as every reading's age is shown."""

from __future__ import annotations

import math
import textwrap
import time
from collections.abc import Callable

import numpy as np
from rich.color import Color
from rich.segment import Segment
from rich.style import Style
from textual import work
from textual.app import ComposeResult
from textual.geometry import Region, Size
from textual.strip import Strip
from textual.widget import Widget

from astiop.robot.camera import CameraFrame, CameraReading

HALF = "▀"
PIXEL_PERIOD_S = {"sixel": 1.0, "tgp": 0.2}  # the fastest a pixel picture is drawn again
CAPTION = Style(bold=True)
DIM = Style(dim=True)


def fit(width: int, height: int, cols: int, rows: int) -> tuple[int, int]:
    """The most cells (cols, rows) a width x height image fills at its aspect, two pixels a
    cell high."""
    if width <= 0 or height <= 0 or cols <= 0 or rows <= 0:
        return 0, 0
    c = cols
    r = math.ceil(c * height / width / 2)
    if r > rows:
        r = rows
        c = max(1, round(2 * r * width / height))
    return min(c, cols), r


_COLOURS: dict[int, Color] = {}  # by 0xRRGGBB, each channel cut to 5 bits: at most 32,768
_STYLES: dict[int, Style] = {}  # by (upper << 24) | lower
MAX_STYLES = 65_536  # a camera's new colour pairs each frame: forgotten past this many


def _colour(rgb: int) -> Color:
    colour = _COLOURS.get(rgb)
    if colour is None:
        colour = _COLOURS[rgb] = Color.from_rgb(rgb >> 16, (rgb >> 8) & 255, rgb & 255)
    return colour


def half_blocks(pixels: np.ndarray, cols: int, rows: int) -> list[Strip]:
    """`pixels` (h, w, 3) sampled to cols x 2*rows (nearest), a strip per row of cells; a run
    of equal cells is one segment. Colours keep 5 bits a channel (what a terminal's cell
    shows of a camera), so a frame's styles are mostly made already."""
    h, w = pixels.shape[:2]
    ys = np.minimum(((np.arange(2 * rows) + 0.5) * h / (2 * rows)).astype(int), h - 1)
    xs = np.minimum(((np.arange(cols) + 0.5) * w / cols).astype(int), w - 1)
    small = (pixels[ys][:, xs] & 0xF8).astype(np.int64)
    rgb = (small[..., 0] << 16) | (small[..., 1] << 8) | small[..., 2]  # (2 rows, cols)
    keys = (rgb[0::2] << 24) | rgb[1::2]
    if len(_STYLES) > MAX_STYLES:
        _STYLES.clear()
    change = np.ones(keys.shape, dtype=bool)
    change[:, 1:] = keys[:, 1:] != keys[:, :-1]
    strips = []
    for row, starts in zip(keys.tolist(), (np.flatnonzero(c).tolist() for c in change)):
        segments = []
        for i, start in enumerate(starts):
            key = row[start]
            style = _STYLES.get(key)
            if style is None:
                style = _STYLES[key] = Style.from_color(_colour(key >> 24), _colour(key & 0xFFFFFF))
            end = starts[i + 1] if i + 1 < len(starts) else cols
            segments.append(Segment(HALF * (end - start), style))
        strips.append(Strip(segments, cols))
    return strips


def caption(reading: CameraReading, now: float | None, width: int = 0) -> list[Strip]:
    """The caption's lines: one with a frame; with none, why, wrapped to `width` (0: one line)."""
    frame = reading.frame
    if frame is None:
        note = reading.note or "no camera"
        lines = textwrap.wrap(note, width - len("camera ")) if width > len("camera ") + 8 else []
        lines = lines or [note]
        first = Strip([Segment("camera ", CAPTION), Segment(lines[0], DIM)])
        return [
            first,
            *(Strip([Segment(" " * len("camera ")), Segment(line, DIM)]) for line in lines[1:]),
        ]
    age = "age unknown" if frame.at is None or now is None else f"{max(0.0, now - frame.at):.1f}s"
    text = f"{frame.topic} {frame.width}×{frame.height} {frame.encoding}"
    return [Strip([Segment("camera ", CAPTION), Segment(age + " "), Segment(text, DIM)])]


class CameraView(Widget):
    """Reads the camera through `read` (the gateway's) in a thread at `hz` while its screen is
    shown; `clock` is the robot's clock as last sampled (`RobotState.t`), for the frame's age."""

    DEFAULT_CSS = """
    CameraView { height: 13; border: round $primary-darken-2; padding: 0 1; }
    CameraView.-absent { height: auto; }
    CameraView #camera-pixels { margin-top: 1; width: auto; height: 1fr; }
    """

    def __init__(
        self,
        read: Callable[[], CameraReading],
        clock: Callable[[], float | None],
        hz: float = 5.0,
        pixels: str | None = None,
        **kw,
    ):
        """`pixels`: 'sixel' or 'tgp' where the terminal draws images (`camera_pixels.detect`),
        None for half-block cells."""
        super().__init__(**kw)
        self._read, self._clock, self._hz = read, clock, hz
        self._pixels_kind = pixels
        self._pixels: Widget | None = None
        self._pixels_digest: tuple | None = None
        self._pixels_at = -math.inf
        self.reading = CameraReading(None, "reading…")
        self._strips: list[Strip] = []
        self._drawn_for: tuple | None = None
        self._reading = False
        self._digest: tuple | None = None

    def compose(self) -> ComposeResult:
        if self._pixels_kind is not None:
            from astiop.widgets.camera_pixels import pixel_widget

            self._pixels = pixel_widget(self._pixels_kind)
            yield self._pixels

    def on_mount(self) -> None:
        self.set_interval(1.0 / self._hz, self.read_frame)
        self.read_frame()

    def read_frame(self) -> None:
        """One read at a time (a slow robot is not asked again meanwhile), and only while the
        screen is shown."""
        if self._reading or not self.screen.is_current:
            return
        self._reading = True
        self._read_in_thread()

    @work(thread=True, group="camera", exit_on_error=False)
    def _read_in_thread(self) -> None:
        try:
            reading = self._read()
        except Exception as exc:  # noqa: BLE001 - said in the view, the next read may do
            reading = CameraReading(None, f"the camera could not be read: {exc}")
        self.app.call_from_thread(self.show, reading)

    def show(self, reading: CameraReading) -> None:
        self._reading = False
        frame = reading.frame
        digest = None if frame is None else (frame.pixels.shape, hash(frame.pixels.tobytes()))
        same = digest is not None and digest == self._digest
        new_note = (reading.absent, reading.note) != (self.reading.absent, self.reading.note)
        self.reading, self._digest = reading, digest
        # a robot with no camera keeps only its note's lines (the Dashboard's rows go to the
        # panels below); back to its size when a frame can come
        self.set_class(reading.absent, "-absent")
        if reading.absent and new_note:
            self.refresh(layout=True)
        if self._pixels is not None:
            self._draw_pixels(frame, digest)
        if same:  # the same picture (a robot standing still): only its age is drawn again
            self.refresh(Region(0, 0, self.size.width, 1))
        else:
            self.refresh()

    def _draw_pixels(self, frame: CameraFrame | None, digest: tuple | None) -> None:
        """A new picture to the pixel widget, at most every PIXEL_PERIOD_S (a Sixel frame is
        encoded on the screen's thread: ~0.1 s for a photo at 270×200 px on 2 cores); one
        held back is drawn at the next read after that."""
        now = time.monotonic()
        kind = self._pixels_kind or ""
        if digest == self._pixels_digest or now - self._pixels_at < PIXEL_PERIOD_S.get(kind, 0):
            return
        from PIL import Image

        self._pixels_digest, self._pixels_at = digest, now
        picture = None if frame is None else Image.fromarray(frame.pixels, "RGB")
        self._pixels.image = picture  # type: ignore[union-attr]  # textual-image's widget

    def _image_strips(self) -> list[Strip]:
        frame: CameraFrame | None = self.reading.frame
        if frame is None or self._pixels is not None:  # drawn as pixels by its child
            return []
        key = (self._digest, self.size.width, self.size.height)
        if key != self._drawn_for:  # a new frame, or a new size: drawn once
            cols, rows = fit(frame.width, frame.height, self.size.width, self.size.height - 1)
            self._strips = half_blocks(frame.pixels, cols, rows) if cols and rows else []
            self._drawn_for = key
        return self._strips

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        return len(caption(self.reading, None, width))

    def render_line(self, y: int) -> Strip:
        base, width = self.rich_style, self.size.width
        lines = caption(self.reading, self._clock(), width)
        if y < len(lines):
            return lines[y].apply_style(base).extend_cell_length(width, base).crop(0, width)
        strips = self._image_strips()
        if y - 1 < len(strips):
            return strips[y - 1].extend_cell_length(width, base)
        return Strip.blank(width, base)
