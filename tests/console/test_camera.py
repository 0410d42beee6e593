"""The robot's camera: the simulator's first-person view of its warehouse, its frames as
sensor_msgs messages, read through the robot layer and drawn on the Dashboard."""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest

from astiop.robot.camera import ImageError, decode, read_camera
from astiop.sim import messages as sm
from astiop.sim.camera import LOOKS, CameraSpec
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.images import image_message
from astiop.transports.simulator.backend import SimBackend
from tests.tui_helpers import console, wait_for

DOCK_FACING = (4.0, 3.0, math.pi)  # 2.95 m from the charging station, looking at it
SPEC = CameraSpec()


def frame_at(pose, **kw) -> np.ndarray:
    _, pixels = Simulator(seed=0, start=pose, **kw).camera_image()
    return pixels


def dominant(rgb) -> str:
    r, g, b = (int(v) for v in rgb)
    return "red" if r > 1.5 * max(g, b) else "green" if g > 1.5 * max(r, b) else "other"


def rows_of(pixels: np.ndarray, column: int, colour: str) -> int:
    return sum(dominant(p) == colour for p in pixels[:, column])


def test_facing_the_charging_station_the_centre_is_green_and_its_sides_are_not():
    pixels = frame_at(DOCK_FACING)
    assert pixels.shape == (SPEC.height, SPEC.width, 3) and pixels.dtype == np.uint8
    mid = SPEC.width // 2
    assert all(dominant(pixels[SPEC.height // 2, c]) == "green" for c in range(mid - 8, mid + 8))
    # the station is 0.8 m wide at 2.95 m: about ±19 px of 160 at 60°; the wall beyond it
    assert dominant(pixels[SPEC.height // 2, 10]) == "other"
    assert dominant(pixels[SPEC.height // 2, SPEC.width - 10]) == "other"


def test_a_nearer_thing_stands_taller_by_the_inverse_of_its_distance():
    """The CPS storage (red, 1.0 m high, its face at x = 38.6) from 4.55 m and from 2.15 m: a
    pinhole's span f * h / d (f = 80 / tan 30° px)."""
    far = frame_at((33.6, 21.0, 0.0))
    near = frame_at((36.0, 21.0, 0.0))
    mid = SPEC.width // 2
    far_rows, near_rows = rows_of(far, mid, "red"), rows_of(near, mid, "red")
    f = SPEC.focal_px
    assert near_rows > far_rows
    assert abs(far_rows - f * 1.0 / (38.6 - 33.6 - SPEC.mount_x)) <= 1.5
    assert abs(near_rows - f * 1.0 / (38.6 - 36.0 - SPEC.mount_x)) <= 1.5


def test_a_wall_nearer_is_a_taller_column():
    """The east wall (3 m, taller than the view at these distances above the camera): its
    span below the horizon is f * 0.5 / d, so the nearer, the further down it reaches."""
    far, near = frame_at((33.0, 12.0, 0.0)), frame_at((37.5, 12.0, 0.0))
    floor = np.asarray(LOOKS["wall"][0])

    def wall_rows(pixels):  # wall pixels are grey, not the floor's brown: R and B close
        col = pixels[:, SPEC.width // 2].astype(int)
        return int(sum(abs(p[0] - p[2]) < 12 and p[0] > 40 for p in col))

    assert floor is not None and wall_rows(near) > wall_rows(far) + 20


def test_obstacles_and_other_robots_are_seen():
    sim = Simulator(seed=0, start=(6.0, 12.0, 0.0))
    before = sim.camera_image()[1].copy()
    sim.add_obstacle("person", 8.0, 12.0)
    sim.step(0.25)  # the next frame
    after = sim.camera_image()[1]
    orange = np.asarray(LOOKS["person"][0]) * 0.5
    column = after[:, SPEC.width // 2].astype(float)
    assert not np.array_equal(before, after)
    assert (np.abs(column - orange).sum(1) < 120).sum() > 10  # the hi-vis vest, shaded by distance


def test_the_image_message_fields():
    at, pixels = Simulator(seed=0, start=DOCK_FACING).camera_image()
    msg = sm.image(at, pixels)
    assert (msg["height"], msg["width"], msg["encoding"]) == (120, 160, "rgb8")
    assert msg["step"] == 160 * 3 and len(msg["data"]) == 120 * 160 * 3
    assert msg["header"]["frame_id"] == "camera" and msg["is_bigendian"] == 0
    # row-major from the top row, red green blue
    assert tuple(msg["data"][:3]) == tuple(pixels[0, 0])
    png = sm.compressed_image(at, pixels)
    from PIL import Image

    assert png["format"] == "rgb8; png compressed rgb8"
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(png["data"])).convert("RGB")), pixels)


def test_the_simulator_publishes_its_frames_at_the_cameras_rate(tmp_path):
    backend = SimBackend(Simulator(seed=0, start=DOCK_FACING), Store(tmp_path / "s.db"))
    spec = backend.catalog.topics["/camera/image_raw"]
    assert spec.rate_hz == SPEC.rate_hz and spec.type == "sensor_msgs/msg/Image"
    assert backend.catalog.profile.name("camera") == "/camera/image_raw"
    backend.sim.step(0.5)
    times = backend.message_times(["/camera/image_raw"])
    assert times["/camera/image_raw"] == pytest.approx(0.4)  # the frame of 0.4-0.6 s
    image = backend.image("/camera/image_raw")
    assert image is not None and (image.width, image.height, image.at) == (160, 120, 0.4)


def test_decoding_reads_the_encodings_said_and_refuses_the_others():
    px = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)

    def msg(encoding, data, step=0, width=3):
        fields = {"width": width, "height": 2, "encoding": encoding, "step": step, "data": data}
        return image_message("/cam", fields, 1.0)

    assert np.array_equal(decode(msg("rgb8", px.tobytes())), px)
    assert np.array_equal(decode(msg("bgr8", px[:, :, ::-1].tobytes())), px)
    mono = decode(msg("mono8", bytes([5, 6, 7, 0, 8, 9, 10, 0]), step=4))  # padded rows
    assert mono.shape == (2, 3, 3) and mono[1, 2].tolist() == [10, 10, 10]
    with pytest.raises(ImageError, match="bayer_rggb8"):
        decode(msg("bayer_rggb8", px.tobytes()))
    with pytest.raises(ImageError, match="do not hold"):
        decode(msg("rgb8", px.tobytes()[:-1]))
    broken = image_message("/cam", {"format": "jpeg", "data": b"not a jpeg"}, 1.0)
    with pytest.raises(ImageError, match="jpeg"):
        decode(broken)


def test_a_robot_without_a_camera_reads_no_camera(tmp_path):
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy

    backend = SimBackend(Simulator(seed=0, camera=None), Store(tmp_path / "g.db"))
    gateway = RobotGateway(backend, SafetyPolicy())
    assert "/camera/image_raw" not in gateway.catalog.topics
    reading = read_camera(gateway)
    assert reading.frame is None and reading.note == "no camera" and reading.absent


def _cells(view) -> list[list[tuple]]:
    """The drawn cells: (character, foreground RGB, background RGB) per cell of each row."""
    rows = []
    for y in range(1, view.size.height):
        cells = []
        for seg in view.render_line(y):
            style = seg.style
            fg = style.color.triplet if style and style.color else None
            bg = style.bgcolor.triplet if style and style.bgcolor else None
            cells += [(ch, fg and tuple(fg), bg and tuple(bg)) for ch in seg.text]
        rows.append(cells)
    return rows


async def test_the_dashboard_draws_the_camera_in_half_blocks(tmp_path):
    from astiop.widgets.camera_view import CameraView

    app = console(tmp_path, sim=Simulator(seed=0, start=DOCK_FACING))
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.screen.query_one(CameraView)
        await app.workers.wait_for_complete()
        await pilot.pause()
        frame = view.reading.frame
        assert frame is not None and frame.topic == "/camera/image_raw"
        caption = "".join(seg.text for seg in view.render_line(0))
        assert caption.startswith("camera 0.0s /camera/image_raw 160×120 rgb8"), caption
        rows = [r for r in _cells(view) if r and r[0][0] == "▀"]
        assert len(rows) >= 8
        middle = rows[len(rows) // 2]
        drawn = [c for c in middle if c[0] == "▀"]
        centre = drawn[len(drawn) // 2]
        # the upper and lower pixel of the centre cell: the station's green
        assert dominant(centre[1]) == "green" and dominant(centre[2]) == "green"
        assert dominant(drawn[0][1]) == "other"  # the wall beside it


async def test_a_terminal_that_draws_images_gets_the_frame_as_sixel_pixels(tmp_path):
    """Where the terminal draws Sixel (asked as the console starts), the frame goes whole to
    textual-image's widget, which writes it as one Sixel picture; no half-block cells."""
    from PIL import Image

    from astiop.widgets.camera_view import CameraView

    app = console(tmp_path, sim=Simulator(seed=0, start=DOCK_FACING))
    app.camera_pixels = "sixel"  # what `camera_pixels.detect()` says in xterm -ti vt340
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.screen.query_one(CameraView)
        await app.workers.wait_for_complete()
        await pilot.pause()
        frame = view.reading.frame
        assert frame is not None
        pixels = app.screen.query_one("#camera-pixels")
        picture = pixels.image  # type: ignore[attr-defined]
        assert isinstance(picture, Image.Image) and picture.size == (frame.width, frame.height)
        assert np.array_equal(np.asarray(picture), frame.pixels)  # the frame as published
        assert not [r for r in _cells(view) if r and r[0][0] == "▀"]
        (impl,) = pixels.children
        drawn = "".join(seg.text for strip in impl.render_lines(impl.size.region) for seg in strip)
        assert re.search(r'\x1bP0;0;0q"1;1;\d+;\d+#', drawn), drawn[:80]  # one Sixel picture
        colours = re.findall(r"#\d+;2;(\d+);(\d+);(\d+)", drawn)  # its registers, in %
        assert "green" in {dominant(int(v) * 255 // 100 for v in c) for c in colours}


def test_the_pixels_are_asked_of_a_terminal_only():
    from astiop.widgets.camera_pixels import detect

    assert detect("cells") is None
    assert detect() is None  # pytest's output is no terminal: half-block cells


async def test_the_dashboard_says_no_camera_on_a_robot_without_one(tmp_path):
    from astiop.widgets.camera_view import CameraView

    app = console(tmp_path, sim=Simulator(seed=0, camera=None))
    async with app.run_test(size=(120, 40)) as pilot:
        await app.workers.wait_for_complete()
        await pilot.pause()
        view = app.screen.query_one(CameraView)
        assert "".join(s.text for s in view.render_line(0)).startswith("camera no camera")
        assert view.size.height == 1  # collapsed to its caption: the rows go to the panels below
        assert view.reading.absent


async def test_why_no_frame_comes_is_said_whole_on_a_narrow_panel():
    """The CLI transport's reason (longer than the panel is wide) wraps instead of being cut."""
    from textual.app import App

    from astiop.robot.camera import CameraReading
    from astiop.widgets.camera_view import CameraView

    note = "/camera/image_raw: the ros2 CLI transport reads no camera frames (rclpy does)"

    class Panel(App):
        def compose(self):
            yield CameraView(lambda: CameraReading(None, note, absent=True), lambda: None)

    app = Panel()
    async with app.run_test(size=(48, 20)) as pilot:
        view = app.query_one(CameraView)
        # the panel takes the note's lines once its class changed (a loaded machine may show
        # the frame's rows a moment before)
        await wait_for(
            pilot, lambda: view.reading.absent and 1 < view.size.height < 6, 10, "wrapped"
        )
        shown = [view.render_line(y).text for y in range(view.size.height)]
        assert " ".join(" ".join(shown).split()) == "camera " + note
        assert view.size.height == len(shown) < 6


def test_a_session_keeps_the_camera_once_a_second_and_replays_it(tmp_path):
    """The recording keeps the camera's PNG frames (its compressed topic), at most one a second
    of robot time; the replay's camera reads them as the live robot's."""
    from astiop.recording.reader import Recording
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.transports.replay.backend import open_replay
    from tests.recordings import record_trip

    path = record_trip(tmp_path)
    recording = Recording(path)
    counts = recording.counts()
    seconds = (recording.end_ns - recording.start_ns) / 1e9
    assert "/camera/image_raw" not in counts
    assert seconds - 1 <= counts["/camera/image_raw/compressed"] <= seconds + 1, (counts, seconds)
    backend = open_replay(path, paused=True)
    backend.playback.seek(seconds / 2)
    reading = read_camera(RobotGateway(backend, SafetyPolicy()))
    frame = reading.frame
    assert frame is not None, reading.note
    assert frame.topic == "/camera/image_raw/compressed" and frame.pixels.shape == (120, 160, 3)
    assert frame.encoding == "rgb8; png compressed rgb8"


async def test_asked_about_the_camera_the_simulators_robot_says_its_frame_never_its_pixels(
    tmp_path,
):
    from astiop.agent.models.specs import open_endpoint
    from astiop.agent.turn import Agent
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy

    store = Store(tmp_path / "a.db")
    sim = Simulator(seed=0, start=DOCK_FACING)
    sim.step(0.3)
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy())
    agent = Agent(gateway, open_endpoint("rules"), store, confirm=lambda _c: True)
    r = await agent.turn("read the camera")  # "what does it see?" is the view (test_view.py)
    assert [c.command for c in r.commands] == ["ros2 topic echo /camera/image_raw --once"]
    assert "camera image 160 x 120 px, rgb8, 57600 bytes" in r.answer, r.answer
    assert r.commands[0].values["data_bytes"] == 57600 and "data" not in r.commands[0].values
    out = r.commands[0].output  # as ros2 topic echo prints it: the first 128 values, then '...'
    assert "!!binary" not in out and out.count("\n- ") == 129 and "- '...'" in out
