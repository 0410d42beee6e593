"""`astiop estop` from a second shell against another process's running timed publish.

    python benchmarks/estop_latency.py [--repeats 5] [--kinds rclpy,cli] [--domain 86]

Each repeat, in fresh processes: `astiop exec --yes "ros2 topic pub -t 300 -r 10 /cmd_vel ..."`
drives the robot; once its Twists arrive, `astiop estop` starts (t0). Measured:
- latch: t0 -> the latch written in the shared database (its `engaged_at`);
- ended: the latch -> the other process's last moving Twist at the robot (how fast it followed:
  the E-STOP comes at a random moment between two of the publish's Twists, 100 ms apart, so a
  process that did not follow would show up to +100 ms here);
- last moving Twist: t0 -> the last moving Twist at the robot;
- estop zero: t0 -> the first zero Twist at the robot;
- speed zero (rclpy only): t0 -> the robot's own /odom speed under 0.01 m/s;
- exec ended: t0 -> the publishing `astiop exec` process exited.
With --stations the publishing `astiop exec` is another station, on a database of its own: it
follows the E-STOP only as said on the robot's graph (rclpy: robot/station_latch.py), and
"last moving Twist" is how long that took from the press.
Kinds: rclpy, against `astiop sim node` on real DDS (Twists taken at the robot's side by
tests/cmd_vel_probe.py); cli, against the emulated `ros2` (tests/emulator.py, --latency-ms of
start-up per call, the robot logs each Twist's arrival). time.monotonic() and time.time() are
system-wide, so every process's clock agrees. Ends with a Markdown table (median / worst).

DDS stays on the loopback: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_LOCALHOST_ONLY=1 and
ROS_DOMAIN_ID (--domain) for this process and every one it starts.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.ros import until  # noqa: E402

PUBLISH = "ros2 topic pub -t 300 -r 10 /cmd_vel geometry_msgs/msg/Twist '{linear: {x: -0.3}}'"


def cli(db: Path, *args: str) -> list[str]:
    return [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2", *args]


def latch_at(db: Path) -> float | None:
    with sqlite3.connect(db) as conn:
        row = conn.execute("SELECT engaged, engaged_at FROM estop WHERE id = 1").fetchone()
    return row[1] if row and row[0] else None


class Probe:
    """tests/cmd_vel_probe.py: each Twist's arrival at the robot (monotonic, vx)."""

    def __init__(self, env: dict):
        self.proc = subprocess.Popen(
            [sys.executable, str(ROOT / "tests" / "cmd_vel_probe.py")],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        self.twists: list[tuple[float, float]] = []
        self.ready = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            msg = json.loads(line)
            if msg.get("ready"):
                self.ready.set()
            elif "mono" in msg:
                self.twists.append((msg["mono"], msg["x"]))

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(10)


class Console:
    """What the console's ctrl+e runs (SafetyKeys._estop: gateway.estop()), in a console's gateway that
    is up before the trial, on the same database and robot."""

    def __init__(self, db: Path, transport: str, env: dict):
        from astiop.config import load_settings
        from astiop.robot.factory import make_robot_gateway
        from astiop.store import Store

        os.environ.update({k: v for k, v in env.items() if k in ("PATH", "ROS_DISTRO")})
        robot = {"backend": "ros2", "ros2_transport": transport}
        settings = load_settings({"robot": robot}, env={}, path=db.with_suffix(".toml"))
        self.store = Store(db)
        self.gateway = make_robot_gateway(settings, self.store, realtime=True, who="console")
        self.gateway.start()

    def estop(self) -> None:
        self.gateway.estop()

    def close(self) -> None:
        self.gateway.release_estop()
        self.gateway.close()
        self.store.close()


STATIONS = False  # --stations: the publisher on a database of its own


def one_trial(
    kind: str, env: dict, work: Path, twists, odom=None, trigger: str = "astiop estop"
) -> dict[str, float]:
    db = work / f"{kind}-{time.monotonic_ns()}.db"
    other = db.with_name(db.stem + "-b.db") if STATIONS else db
    subprocess.run(cli(db, "estop", "--release", "--yes"), env=env, capture_output=True)
    transport = env["ASTIOP_ROBOT__ROS2_TRANSPORT"]
    console = Console(db, transport, env) if trigger == "ctrl+e" else None
    publisher = subprocess.Popen(
        cli(other, "exec", "--yes", PUBLISH), env=env, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    n0 = len(twists())
    if not until(lambda: sum(1 for _, x in twists()[n0:] if x != 0.0) >= 5, 60, step=0.01):
        publisher.kill()
        raise RuntimeError(f"{kind}: the timed publish never reached the robot")
    time.sleep(random.uniform(0.0, 0.1))  # anywhere between two of the publish's Twists
    t0_wall, t0 = time.time(), time.monotonic()
    if console is not None:
        console.estop()
    else:
        estop = subprocess.run(cli(db, "estop"), env=env, capture_output=True, text=True)
        if estop.returncode != 0:
            raise RuntimeError(f"{kind}: astiop estop failed: {estop.stderr}")
    exited = None
    try:
        publisher.wait(20)
        exited = time.monotonic() - t0
    except subprocess.TimeoutExpired:
        publisher.kill()
    time.sleep(1.5)
    got = twists()[n0:]
    moving = [t for t, x in got if x != 0.0]
    zeros = [t for t, x in got if x == 0.0 and t >= t0]
    latch = latch_at(db)
    row = {
        "latch": latch - t0_wall if latch else float("nan"),
        "ended": (moving[-1] - t0) - (latch - t0_wall) if latch else float("nan"),
        "last moving Twist": moving[-1] - t0,
        "estop zero": zeros[0] - t0 if zeros else float("nan"),
        "exec ended": exited if exited is not None else float("nan"),
    }
    if odom is not None:
        still = [t for t, v in odom() if t >= t0 and v < 0.01]
        row["speed zero"] = still[0] - t0 if still else float("nan")
    if console is not None:
        console.close()
    subprocess.run(cli(db, "estop", "--release", "--yes"), env=env, capture_output=True)
    return row


def run_rclpy(env: dict, work: Path, repeats: int, trigger: str) -> list[dict]:
    from tests.ros import RosClient, sim_node

    env = {**env, "ASTIOP_ROBOT__ROS2_TRANSPORT": "rclpy"}
    rows = []
    with sim_node(speed=1.0):
        probe = Probe(env)
        probe.ready.wait(30)
        client = RosClient("estop_bench")
        from nav_msgs.msg import Odometry

        got = client.collect(Odometry, "/odom")

        def odom():
            return [(t, abs(m.twist.twist.linear.x)) for t, m in list(got)]

        db = work / "undock.db"
        undock = cli(db, "exec", "--yes", "ros2 service call /undock std_srvs/srv/Trigger")
        subprocess.run(undock, env=env, capture_output=True, check=True)
        try:
            for i in range(repeats):
                row = one_trial("rclpy", env, work, lambda: list(probe.twists), odom, trigger)
                rows.append(row)
                print(f"rclpy {i + 1}/{repeats}: {row}", file=sys.stderr)
        finally:
            probe.close()
            client.close()
    return rows


def run_cli(env: dict, work: Path, repeats: int, latency_ms: int, trigger: str) -> list[dict]:
    from tests.emulator import cmd_vel_received, emulated_robot

    rows = []
    with emulated_robot(latency_ms=latency_ms, speed=1.0) as folder:
        env = {
            **env,
            "PATH": f"{folder}{os.pathsep}{env['PATH']}",
            "ROS_DISTRO": "jazzy",
            "ASTIOP_ROBOT__ROS2_TRANSPORT": "cli",
        }

        def twists():
            return [(t["mono"], t["twist"]["linear"]["x"]) for t in cmd_vel_received(folder)]

        for i in range(repeats):
            rows.append(one_trial("cli", env, work, twists, trigger=trigger))
            print(f"cli {i + 1}/{repeats}: {rows[-1]}", file=sys.stderr)
    return rows


def table(results: dict[str, list[dict]]) -> str:
    keys = ["latch", "ended", "last moving Twist", "estop zero", "speed zero", "exec ended"]
    lines = [
        "| from the E-STOP's start | " + " | ".join(results) + " |",
        "|---|" + "---|" * len(results),
    ]
    for key in keys:
        cells = []
        for rows in results.values():
            values = [r[key] for r in rows if key in r and r[key] == r[key]]
            cells.append(
                f"{statistics.median(values) * 1000:.0f} / {max(values) * 1000:.0f} ms"
                if values
                else "-"
            )
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--kinds", default="rclpy,cli")
    ap.add_argument("--latency-ms", type=int, default=300)
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", 86)))
    ap.add_argument("--stations", action="store_true", help="the publisher on its own database")
    ap.add_argument(
        "--trigger",
        choices=["astiop estop", "ctrl+e"],
        default="astiop estop",
        help="a second shell's `astiop estop`, or a console's ctrl+e (its gateway.estop())",
    )
    args = ap.parse_args()
    global STATIONS
    STATIONS = args.stations
    os.environ.update(
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_LOCALHOST_ONLY="1",
        ROS_DOMAIN_ID=str(args.domain),
    )
    env = {**os.environ, "ASTIOP_LLM__MODEL": "rules"}
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        kinds = args.kinds.split(",")
        if "rclpy" in kinds:
            name = "rclpy (sim node, real DDS)"
            results[name] = run_rclpy(env, work, args.repeats, args.trigger)
        if "cli" in kinds:
            name = f"cli (emulated, {args.latency_ms} ms a call)"
            results[name] = run_cli(env, work, args.repeats, args.latency_ms, args.trigger)
    where = "another station (its own database)" if args.stations else "the same database"
    print(f"trigger: {args.trigger}; publisher on {where}; load {os.getloadavg()[0]:.2f}")
    print(table(results))


if __name__ == "__main__":
    main()
