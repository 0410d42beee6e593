"""What the camera costs: the simulator's render of one frame, and the console's decode and draw
of a frame in half-block cells (80 x 40 by default), for the simulator's 160 x 120 rgb8, a
640 x 480 bgr8 camera (noise: every cell a new colour pair) and a 640 x 480 JPEG.

    python benchmarks/camera.py [--cols 80] [--rows 40] [--frames 100]
"""

from __future__ import annotations

import argparse
import io
import statistics
import time

import numpy as np
from PIL import Image

from astiop.robot.camera import decode
from astiop.sim import messages as sm
from astiop.sim.simulator import Simulator
from astiop.transports.images import image_message
from astiop.widgets.camera_view import half_blocks

POSES = {
    "facing the charging station": (4.0, 3.0, 3.1416),
    "down an aisle, a person ahead": (8.0, 9.0, 0.3),
    "the east wall, 1 m": (38.0, 12.0, 0.0),
}


def ms(run, n: int) -> tuple[float, float]:
    run()
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        run()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times), max(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cols", type=int, default=80)
    ap.add_argument("--rows", type=int, default=40)
    ap.add_argument("--frames", type=int, default=100)
    args = ap.parse_args()
    n, cols, rows = args.frames, args.cols, args.rows
    for what, pose in POSES.items():
        sim = Simulator(seed=0, start=pose)
        sim.add_obstacle("person", 11.0, 9.2)
        camera = sim.camera
        assert camera is not None

        def render(camera=camera, sim=sim) -> None:
            camera._held = None  # a new frame each time, as a moving robot's
            sim.camera_image()

        med, worst = ms(render, n)
        print(f"render 160x120, {what}: {med:.2f} ms median, {worst:.2f} ms worst")
    at, pixels = Simulator(seed=0, start=(8.0, 9.0, 0.3)).camera_image()
    rng = np.random.default_rng(0)
    noise = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    y, x = np.mgrid[0:480, 0:640]
    smooth = np.stack([x * 255 // 640, y * 255 // 480, (x + y) * 255 // 1120], -1)
    jpeg = io.BytesIO()
    Image.fromarray(smooth.astype(np.uint8)).save(jpeg, "JPEG")
    frames = {
        "the simulator's 160x120 rgb8": image_message("/c", sm.image(at, pixels), at),
        "640x480 bgr8 noise": image_message(
            "/c",
            {
                "width": 640,
                "height": 480,
                "encoding": "bgr8",
                "step": 1920,
                "data": noise.tobytes(),
            },
            0.0,
        ),
        "640x480 JPEG": image_message("/c", {"format": "jpeg", "data": jpeg.getvalue()}, 0.0),
    }
    for what, msg in frames.items():
        med, worst = ms(lambda msg=msg: half_blocks(decode(msg), cols, rows), n)
        print(f"decode + draw {cols}x{rows} cells, {what}: {med:.2f} ms median, {worst:.2f} worst")


if __name__ == "__main__":
    main()
