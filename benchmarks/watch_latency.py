"""How soon a watch fires after the reading that makes it true, over real DDS.

    python benchmarks/watch_latency.py [--repeats 15] [--domain 87]

`astiop sim node` is the robot (its battery at 85 %, published at 20 Hz); `astiop watch run
--json` on `--robot ros2` (rclpy) keeps the watch "battery below 50 %, every time" — the same
WatchRunner a console runs on its own thread. This process publishes a BatteryState at 30 % on
the robot's battery topic (t0: the first, time.monotonic(), system-wide), again every 5 ms
(the simulator's own 85 % comes between them at 20 Hz, and one reading at 30 % could be
overwritten before it is looked at), until it reads the alert's JSON line (t1); the
simulator's next 85 % clears the watch for the next repeat. Measured: t0 -> t1 (DDS,
the runner's look for a new reading every 10 ms, the store's write, the line on a pipe).

DDS stays on the loopback: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_LOCALHOST_ONLY=1 and
ROS_DOMAIN_ID (--domain) for this process and every one it starts.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.ros import RosClient, SimNode  # noqa: E402

TOPIC = "/battery_status"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--domain", type=int, default=87)
    args = ap.parse_args()
    os.environ.update(
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_LOCALHOST_ONLY="1",
        ROS_DOMAIN_ID=str(args.domain),
    )  # fmt: skip
    from sensor_msgs.msg import BatteryState

    sim = SimNode(speed=1.0, env=dict(os.environ))
    sim.wait_ready()
    tmp = Path(tempfile.mkdtemp())
    base = [sys.executable, "-m", "astiop", "--db", str(tmp / "w.db"), "--robot", "ros2"]
    subprocess.run([*base, "watch", "add", "--field", "battery", "--below", "50", "--every"],
                   check=True, capture_output=True)  # fmt: skip
    runner = subprocess.Popen([*base, "watch", "run", "--json"], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    fired: list[float] = []
    kinds: list[str] = []
    seen = threading.Event()

    def read() -> None:
        for line in runner.stdout:
            alert = json.loads(line)
            kinds.append(alert["kind"])
            if alert["kind"] == "watch":
                fired.append(time.monotonic())
                seen.set()

    threading.Thread(target=read, daemon=True).start()
    client = RosClient("watch_latency")
    pub = client.node.create_publisher(BatteryState, TOPIC, 10)
    latencies: list[float] = []
    try:
        time.sleep(8.0)  # the runner discovers the robot and its first readings
        for _ in range(args.repeats):
            seen.clear()
            msg = BatteryState(percentage=0.30, voltage=22.0, present=True)
            t0 = time.monotonic()
            while not seen.is_set() and time.monotonic() - t0 < 5.0:
                pub.publish(msg)  # every 5 ms: the robot's own 85 % comes between, at 20 Hz
                seen.wait(0.005)
            if seen.is_set():
                latencies.append((fired[-1] - t0) * 1000)
            # the simulator's 85 % clears it; a clear moves the alert's episode on only 5 s
            # after it fired (watches/evaluator.py: two processes a sample apart)
            time.sleep(5.5)
    finally:
        client.close()
        runner.terminate()
        runner.wait(10)
        sim.stop()
    missed = args.repeats - len(latencies)
    if not latencies:
        raise SystemExit(f"no alert in {args.repeats} tries (alerts seen: {kinds})")
    lat = sorted(latencies)
    print("| reading -> alert (ms) | median | p90 | worst | missed |")
    print("| --- | --- | --- | --- | --- |")
    p90 = lat[min(len(lat) - 1, int(0.9 * len(lat)))]
    print(f"| watch run, rclpy | {statistics.median(lat):.1f} | {p90:.1f} | {lat[-1]:.1f} | "
          f"{missed} |")  # fmt: skip


if __name__ == "__main__":
    main()
