"""Key press to robot, on the emulated ROS 2 robot: E-STOP and teleop through the console.

    python benchmarks/ros2_latency.py [--latency-ms 500] [--repeats 5]

Prints, for each repeat, the time from the key press (Pilot) to the Twist's arrival at the
robot process (time.monotonic is system-wide on Linux, so the two processes agree).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from astiop.app import make_app  # noqa: E402
from astiop.config import load_settings  # noqa: E402
from astiop.store import Store  # noqa: E402
from tests.emulator import cmd_vel_received, emulated_robot  # noqa: E402


async def once(latency_ms: int) -> tuple[float, float, float]:
    with emulated_robot(latency_ms=latency_ms) as robot:
        os.environ["PATH"] = f"{robot}{os.pathsep}{os.environ['PATH']}"
        os.environ["ROS_DISTRO"] = "jazzy"
        cfg = load_settings({"llm": {"model": "rules"}, "robot": {"backend": "ros2"}}, env={})
        app = make_app(cfg, Store(Path(tempfile.mkdtemp()) / "bench.db"))
        async with app.run_test(size=(120, 40)) as pilot:
            gateway = app.services.gateway
            gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=lambda _c: True)
            await asyncio.sleep(3.0)  # undocked; the armed publisher has started
            await pilot.press("f5")
            n0 = len(cmd_vel_received(robot))
            pressed = time.monotonic()
            await pilot.press("w")
            while len(cmd_vel_received(robot)) == n0:
                await asyncio.sleep(0.005)
            first_key = cmd_vel_received(robot)[n0]["mono"] - pressed
            for _ in range(40):  # the key held: terminals repeat it ~every 50 ms
                await pilot.press("w")
                await asyncio.sleep(0.05)
            held = [m["mono"] for m in cmd_vel_received(robot)[n0:]]
            repeat_key = max(b - a for a, b in zip(held, held[1:]))  # worst gap while held
            await asyncio.sleep(0.2)
            pressed = time.monotonic()
            await pilot.press("ctrl+e")
            zero = None
            while zero is None:
                zero = next(
                    (
                        m
                        for m in cmd_vel_received(robot)
                        if m["mono"] >= pressed and m["twist"]["linear"]["x"] == 0.0
                    ),
                    None,
                )
                await asyncio.sleep(0.005)
            return zero["mono"] - pressed, first_key, repeat_key


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--latency-ms", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rows = [asyncio.run(once(args.latency_ms)) for _ in range(args.repeats)]
    for name, i in (
        ("E-STOP key -> zero Twist", 0),
        ("teleop first key -> Twist", 1),
        ("teleop held: worst gap", 2),
    ):
        ms = [r[i] * 1000 for r in rows]
        print(
            f"{name:34s} median {statistics.median(ms):7.1f} ms  max {max(ms):7.1f} ms  "
            f"(n={len(ms)}, ros2 start-up {args.latency_ms} ms)"
        )


if __name__ == "__main__":
    main()
