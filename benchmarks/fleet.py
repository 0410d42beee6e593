"""A fleet of simulated ASTIbots over real DDS, and a console watching it, at N = 1, 5, 10, 25.

    python benchmarks/fleet.py [--robots 1,5,10,25] [--window 10] [--settle 10] [--domain 70]
                               [--discovery-server]

For each N, in fresh processes on a domain of their own (the loopback only):
- `astiop sim node --robots N --prefix astibot_`: seconds to "up as ROS 2 nodes", and its CPU
  (% of one core) over --window seconds with every robot at rest on its dock;
- the physics alone (`SimFleet`, in this process, every robot driving): its real-time factor,
  how many simulated seconds per second one core steps the N robots and their lidars;
- a console, `astiop --robot ros2 --fleet auto` (rclpy), run under tmux as an operator would:
  seconds from its start to the Fleet screen (F7) listing all N robots with a battery; its
  CPU (with every process it started) over --window seconds on the Fleet screen, at once
  (the finder still polls a young graph) and again --settle seconds later;
- ctrl+e sent to that console: milliseconds from the key to the first zero Twist of the last
  robot, each robot's /astibot_i/cmd_vel taken by a probe process of its own (time.monotonic()
  is system-wide on Linux).
With --discovery-server, every process discovers through the Fast DDS Discovery Server (the
wheels' `fast-discovery-server` on 127.0.0.1:11811, the console a super client) instead of
simple discovery. The CLI transport is not measured here: it runs one `ros2` process per read,
per robot.
Ends with a Markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TICK = os.sysconf("SC_CLK_TCK")

PROBE = r"""
import json, os, sys, time, threading
import rclpy
from geometry_msgs.msg import Twist
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
n = int(sys.argv[1])
ctx = rclpy.Context(); rclpy.init(context=ctx)
node = Node("fleet_probe", context=ctx)
def on(i):
    def heard(msg):
        moving = any(abs(v) > 1e-9 for v in (msg.linear.x, msg.linear.y, msg.angular.z))
        print(json.dumps({"robot": i, "mono": time.monotonic(), "zero": not moving}), flush=True)
    return heard
subs = [node.create_subscription(Twist, f"/astibot_{i}/cmd_vel", on(i), 50) for i in range(1, n + 1)]
ex = SingleThreadedExecutor(context=ctx); ex.add_node(node)
print(json.dumps({"ready": True}), flush=True)
threading.Thread(target=lambda: sys.stdin.read() or os._exit(0), daemon=True).start()
while True:
    ex.spin_once(timeout_sec=0.5)
"""


def cpu_s(pid: int) -> float:
    """CPU seconds of a process and every process below it."""
    total = 0.0
    for p in [pid, *descendants(pid)]:
        try:
            fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
            total += (int(fields[11]) + int(fields[12])) / TICK
        except (OSError, IndexError, ValueError):
            pass
    return total


def descendants(pid: int) -> list[int]:
    out = []
    for child in Path(f"/proc/{pid}/task/{pid}/children").read_text().split():
        out += [int(child), *descendants(int(child))]
    return out


def cpu_percent(pid: int, window: float) -> float:
    a, t0 = cpu_s(pid), time.monotonic()
    time.sleep(window)
    return 100.0 * (cpu_s(pid) - a) / (time.monotonic() - t0)


def physics_rtf(n: int, sim_s: float = 5.0) -> float:
    """Simulated seconds per wall second of N robots driving, lidars on, on one core."""
    from astiop.sim.fleet import SimFleet

    fleet = SimFleet([f"astibot_{i}" for i in range(1, n + 1)])
    for robot in fleet.robots:  # off their docks, each in a small circle
        robot.set_cmd_vel(0.15, 0.0, 0.4, timeout=1e9)
    t0 = time.perf_counter()
    fleet.step(sim_s)
    return sim_s / (time.perf_counter() - t0)


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True).stdout


def measure(n: int, domain: int, window: float, env: dict, settle: float) -> dict:
    env = {**env, "ROS_DOMAIN_ID": str(domain)}
    out: dict = {"robots": n}
    t0 = time.monotonic()
    node = subprocess.Popen(
        [sys.executable, "-m", "astiop", "sim", "node", "--robots", str(n), "--prefix",
         "astibot_"],
        env=env, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    for line in node.stderr:
        if "up as ROS 2 nodes" in line:
            break
    out["node_up_s"] = time.monotonic() - t0
    threading.Thread(target=node.stderr.read, daemon=True).start()
    out["node_cpu"] = cpu_percent(node.pid, window)
    out["physics_rtf"] = physics_rtf(n)
    probe = subprocess.Popen(
        [sys.executable, "-c", PROBE, str(n)], env=env, stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    heard: list[dict] = []
    assert json.loads(probe.stdout.readline())["ready"]
    threading.Thread(
        target=lambda: [heard.append(json.loads(line)) for line in probe.stdout], daemon=True
    ).start()
    work = Path(tempfile.mkdtemp(prefix="astiop-fleet-bench-"))
    session = f"fleetbench{n}"
    ds = " ".join(f"{k}={env[k]}" for k in ("ROS_DISCOVERY_SERVER", "ROS_SUPER_CLIENT") if k in env)
    console = (
        f"cd {work} && env ROS_DOMAIN_ID={domain} ASTIOP_LLM__MODEL=rules {ds} "
        f"{sys.executable} -m astiop --db {work / 'c.db'} --robot ros2 --ros2-transport rclpy "
        "--fleet auto"
    )
    tmux("kill-session", "-t", session)
    t0 = time.monotonic()
    tmux("new-session", "-d", "-s", session, "-x", "170", "-y", str(max(40, n + 14)), console)
    pane_pid = int(tmux("display", "-p", "-t", session, "#{pane_pid}").strip())
    listed, asked = None, False
    while time.monotonic() - t0 < 120:
        screen = tmux("capture-pane", "-p", "-t", session)
        if not asked and "model:" in screen:  # the console is up: its Fleet screen
            tmux("send-keys", "-t", session, "F7")
            asked = True
        rows = [ln for ln in screen.splitlines() if "astibot_" in ln and "%" in ln]
        if f"{n} robot{'s' * (n != 1)}:" in screen and len(rows) >= n:
            listed = time.monotonic() - t0
            break
        time.sleep(0.1)
    out["listed_s"] = listed
    out["console_cpu_start"] = cpu_percent(pane_pid, window)  # the fleet still being found
    time.sleep(settle)
    out["console_cpu"] = cpu_percent(pane_pid, window)
    heard.clear()
    pressed = time.monotonic()
    tmux("send-keys", "-t", session, "C-e")
    deadline = time.monotonic() + 10
    firsts: dict[int, float] = {}
    while time.monotonic() < deadline and len(firsts) < n:
        for h in list(heard):
            if h["zero"] and h["mono"] >= pressed:
                firsts.setdefault(h["robot"], h["mono"])
        time.sleep(0.01)
    out["estop_last_ms"] = (max(firsts.values()) - pressed) * 1000 if len(firsts) == n else None
    out["estop_first_ms"] = (min(firsts.values()) - pressed) * 1000 if firsts else None
    tmux("send-keys", "-t", session, "C-q")
    time.sleep(2)
    tmux("kill-session", "-t", session)
    probe.stdin.close()
    probe.terminate()
    node.terminate()
    node.wait(20)
    shutil.rmtree(work, ignore_errors=True)
    return out


def fmt(v, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robots", default="1,5,10,25")
    ap.add_argument("--window", type=float, default=10.0)
    ap.add_argument("--domain", type=int, default=70)
    ap.add_argument("--settle", type=float, default=10.0, help="s after the listing, then CPU")
    ap.add_argument(
        "--discovery-server",
        action="store_true",
        help="discover through the Fast DDS Discovery Server, not simple discovery",
    )
    args = ap.parse_args()
    if shutil.which("tmux") is None:
        sys.exit("fleet.py runs the console under tmux: install tmux")
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_LOCALHOST_ONLY": "1"}
    os.environ.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_LOCALHOST_ONLY="1")
    server = discovery_server(env) if args.discovery_server else None
    rows = []
    for k, n in enumerate(int(x) for x in args.robots.split(",")):
        row = measure(n, args.domain + k, args.window, env, args.settle)
        print(json.dumps(row), flush=True)
        rows.append(row)
    print(
        "\n| robots | node up (s) | node CPU idle (%) | physics RTF (x) | listed (s) "
        "| console CPU, Fleet screen: first window / settled (%) "
        "| E-STOP all: first / last zero Twist (ms) |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['robots']} | {fmt(r['node_up_s'], '.1f')} | {fmt(r['node_cpu'], '.0f')} "
              f"| {fmt(r['physics_rtf'], '.1f')} | {fmt(r['listed_s'], '.1f')} "
              f"| {fmt(r['console_cpu_start'], '.0f')} / {fmt(r['console_cpu'], '.0f')} "
              f"| {fmt(r['estop_first_ms'], '.0f')} / "
              f"{fmt(r['estop_last_ms'], '.0f')} |")  # fmt: skip
    if server is not None:
        server.terminate()


def discovery_server(env: dict) -> subprocess.Popen:
    """The wheels' Fast DDS Discovery Server on the loopback (its libraries are the venv's),
    and every process of the benchmark its client (the console, a super client: the whole
    graph, as ros2 sees it)."""
    venv = Path(sys.prefix)
    libs = [str(venv / "lib"), *map(str, venv.glob("lib/python*/site-packages/ros_fastrtps.libs"))]
    server_env = {**env, "LD_LIBRARY_PATH": ":".join([*libs, env.get("LD_LIBRARY_PATH", "")])}
    exe = shutil.which("fast-discovery-server", path=str(venv / "bin")) or "fast-discovery-server"
    server = subprocess.Popen([exe, "-i", "0", "-l", "127.0.0.1", "-p", "11811"],
                              env=server_env, stdout=subprocess.DEVNULL)  # fmt: skip
    time.sleep(1.0)
    if server.poll() is not None:
        sys.exit("fast-discovery-server did not start")
    env.update(ROS_DISCOVERY_SERVER="127.0.0.1:11811", ROS_SUPER_CLIENT="TRUE")
    return server


if __name__ == "__main__":
    main()
