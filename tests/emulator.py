"""The emulated ROS 2 robot in its own process, for tests of the ros2 path end to end."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# The E-STOP's zero-Twist publisher, started ahead of time and waiting on stdin (Jazzy).
ARMED_ESTOP = [
    "topic",
    "pub",
    "--stdin",
    "-r",
    "10",
    "-t",
    "10",
    "/cmd_vel",
    "geometry_msgs/msg/Twist",
]


@contextlib.contextmanager
def emulated_robot(
    *,
    latency_ms: int = 30,
    distro: str = "jazzy",
    missing: tuple[str, ...] = (),
    speed: float = 1.0,
    daemon_stopped: bool = False,
    folder: Path | None = None,
    processes: list | None = None,
    dds: bool = False,
):
    """`processes`: the robot's process is appended (a test that kills it); `folder`: the one
    a killed robot ran in (its `ros2` is still on PATH), for it to come back. `dds`: no robot
    of its own, the verbs run over real DDS against the robot on this worker's domain."""
    folder = folder or Path(tempfile.mkdtemp(prefix="emu-", dir="/tmp"))  # short: a socket path
    argv = [
        sys.executable,
        "-m",
        "astiop",
        "emulate-ros2",
        "--dir",
        str(folder),
        "--distro",
        distro,
        "--latency-ms",
        str(latency_ms),
        "--speed",
        str(speed),
    ]
    for name in missing:
        argv += ["--missing", name]
    if daemon_stopped:
        argv.append("--daemon-stopped")
    if dds:
        argv.append("--dds")
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    if processes is not None:
        processes.append(proc)
    try:
        deadline = time.monotonic() + 30
        while not _answers(folder / "robot.sock"):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the emulated robot did not start: {proc.stderr.read()}")
            time.sleep(0.05)
        yield folder
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(folder, ignore_errors=True)


def _answers(path: Path) -> bool:
    if not path.exists():
        return False
    with socket.socket(socket.AF_UNIX) as s:
        try:
            s.connect(str(path))
        except OSError:
            return False
    return True


def ros2_log(folder: Path) -> list[dict]:
    """Every call of the emulated `ros2`: its argv and when it started (time.monotonic)."""
    log = folder / "ros2.log"
    if not log.exists():
        return []
    return [json.loads(line) for line in log.read_text().splitlines()]


def ros2_calls(folder: Path) -> list[list[str]]:
    """Every argv the emulated `ros2` was called with, in order."""
    return [entry["argv"] for entry in ros2_log(folder)]


def cmd_vel_received(folder: Path) -> list[dict]:
    """Each Twist the robot received, with its arrival time (time.monotonic, system-wide)."""
    with socket.socket(socket.AF_UNIX) as s:
        s.connect(str(folder / "robot.sock"))
        s.sendall(b'{"op": "cmd_vel_log"}\n')
        data = b""
        while chunk := s.recv(65536):
            data += chunk
    first = json.loads(data.decode().splitlines()[0])
    return json.loads(first["out"])


def on_path(monkeypatch, folder: Path, distro: str = "jazzy") -> None:
    monkeypatch.setenv("PATH", f"{folder}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("ROS_DISTRO", distro)
    # the emulated robot answers only its `ros2` (rclpy would find no robot on DDS)
    monkeypatch.setenv("ASTIOP_ROBOT__ROS2_TRANSPORT", "cli")
