"""The emulated `ros2` executable: parse like ros2cli, pay a start-up delay, ask the robot.

Every call's argv is appended to ros2.log as a JSON line the moment it starts. The output
streams as the robot process sends it; SIGINT is passed to the robot, which stops or cancels
what this call started, as the real client does on Ctrl-C.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import sys
import time

from astiop.ros2.cli_args import build_parser


def _log(folder: str, argv: list[str]) -> None:
    line = json.dumps({"t": time.time(), "mono": time.monotonic(), "argv": argv})
    with open(os.path.join(folder, "ros2.log"), "a", encoding="utf-8") as fh:
        fh.write(line + "\n")


def main(argv: list[str], folder: str) -> int:
    _log(folder, argv)
    with open(os.path.join(folder, "robot.json"), encoding="utf-8") as fh:
        robot = json.load(fh)
    args = build_parser(robot["distro"]).parse_args(argv)  # exits 2 like ros2 on bad usage
    time.sleep(robot["latency_ms"] / 1000.0)  # what importing rclpy and ros2cli costs
    values = vars(args)
    if values.get("stdin"):
        values["stdin_values"] = sys.stdin.read()  # before the node exists, as ros2cli does
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(robot["socket"])
    except OSError:
        print("the emulated robot is not running (start `astiop emulate-ros2`)", file=sys.stderr)
        return 1
    interrupted = []

    def on_sigint(_sig, _frame) -> None:
        if not interrupted:
            interrupted.append(True)
            with contextlib.suppress(OSError):
                sock.sendall(b'{"signal": "INT"}\n')

    signal.signal(signal.SIGINT, on_sigint)
    sock.sendall((json.dumps({"argv": argv, "args": values}) + "\n").encode())
    reader = sock.makefile("r", encoding="utf-8")
    code = 1
    for line in reader:
        msg = json.loads(line)
        if "out" in msg:
            sys.stdout.write(msg["out"])
            sys.stdout.flush()
        elif "err" in msg:
            sys.stderr.write(msg["err"])
            sys.stderr.flush()
        elif "exit" in msg:
            code = int(msg["exit"])
            break
    sock.close()
    return code
