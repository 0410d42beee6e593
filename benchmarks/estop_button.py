"""The page's E-STOP button: from the click (its POST /estop) to the first zero Twist at the robot.

    python benchmarks/estop_button.py [--repeats 5] [--domain 78]

`astiop serve --sim shared --no-warm` with no tab open (the robot is the shared simulator, on the
domain the server picks for it); tests/cmd_vel_probe.py listens to its /cmd_vel on that domain
and stamps each Twist's arrival (time.monotonic(), system-wide). Each repeat: POST /estop as the
page does, then `astiop estop --release --yes` on the server's database and robot. Prints the
median and the worst of: click -> first zero Twist at the robot, click -> the answer.

DDS stays on the loopback: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_LOCALHOST_ONLY=1.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.ros import until  # noqa: E402
from tests.web_console import free_port, start_serve, stop_serve  # noqa: E402


def probe(env: dict) -> tuple[subprocess.Popen, list[tuple[float, float]], threading.Event]:
    proc = subprocess.Popen(
        [sys.executable, str(ROOT / "tests" / "cmd_vel_probe.py")],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    twists: list[tuple[float, float]] = []
    ready = threading.Event()

    def read() -> None:
        for line in proc.stdout:
            msg = json.loads(line)
            if msg.get("ready"):
                ready.set()
            elif "mono" in msg:
                twists.append((msg["mono"], msg["x"]))

    threading.Thread(target=read, daemon=True).start()
    return proc, twists, ready


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--domain", type=int, default=78, help="the server's own (not the robot's)")
    args = ap.parse_args()
    env = {
        **os.environ,
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "ROS_LOCALHOST_ONLY": "1",
        "ROS_DOMAIN_ID": str(args.domain),
        "ASTIOP_LLM__MODEL": "rules",
    }
    clicks, answers = [], []
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "serve.db"
        port = free_port()
        server = start_serve(db, port, "--no-warm", env=env, sim="shared")
        url = f"http://127.0.0.1:{port}"
        try:
            page = urllib.request.urlopen(url + "/").read().decode()
            domain = re.search(r"ROS_DOMAIN_ID=(\d+)", page)[1]
            robot_env = {**env, "ROS_DOMAIN_ID": domain}
            proc, twists, ready = probe(robot_env)
            ready.wait(30)
            time.sleep(3.0)  # the server's gateway has found the base
            release = [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2"]
            for i in range(args.repeats):
                n0 = len(twists)
                request = urllib.request.Request(
                    url + "/estop", method="POST",
                    headers={"Origin": url, "X-Astiop": "estop"}, data=b"",
                )  # fmt: skip
                t0 = time.monotonic()
                body = json.loads(urllib.request.urlopen(request, timeout=60).read())
                answered = time.monotonic() - t0
                until(lambda n0=n0: any(x == 0.0 for _, x in twists[n0:]), 10, step=0.005)
                zero = next((t for t, x in twists[n0:] if x == 0.0 and t >= t0), None)
                if zero is None:
                    raise RuntimeError(f"no zero Twist reached the robot: {body}")
                clicks.append(zero - t0)
                answers.append(answered)
                print(f"{i + 1}/{args.repeats}: zero {clicks[-1] * 1000:.0f} ms, answer "
                      f"{answered * 1000:.0f} ms", file=sys.stderr)  # fmt: skip
                subprocess.run([*release, "estop", "--release", "--yes"], env=robot_env,
                               capture_output=True, timeout=60)  # fmt: skip
                time.sleep(1.5)
            proc.stdin.close()
            proc.wait(10)
        finally:
            stop_serve(server)
    print(f"load average {os.getloadavg()[0]:.2f}; {args.repeats} clicks, no tab open")
    for name, values in (("click -> first zero Twist", clicks), ("click -> answer", answers)):
        print(f"| {name} | {statistics.median(values) * 1000:.0f} / "
              f"{max(values) * 1000:.0f} ms |")  # fmt: skip


if __name__ == "__main__":
    main()
