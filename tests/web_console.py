"""`astiop serve` run as a user runs it, and what its consoles show: the terminal's bytes (the
websocket's binary frames) fed to a VT emulator (pyte), read as text."""

from __future__ import annotations

import contextlib
import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pyte

ENV = {**os.environ, "ASTIOP_LLM__THREADS": "1"}


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def start_serve(
    db: Path,
    port: int,
    *flags: str,
    env: dict | None = None,
    model: str = "rules",
    sim: str = "per-tab",
):
    """`astiop --db DB --model MODEL serve --port PORT --sim SIM FLAGS`, once its port accepts."""
    args = [sys.executable, "-m", "astiop", "--db", str(db), "--model", model, "serve"]
    args += ["--sim", sim]
    log = open(db.parent / f"serve-{port}.log", "wb")  # noqa: SIM115 - closed with the process
    proc = subprocess.Popen(
        [*args, "--port", str(port), *flags],
        env=env or ENV,
        stdout=log,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
    )
    proc.log_path = db.parent / f"serve-{port}.log"
    deadline = time.monotonic() + 90  # a shared simulator starts first
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            return proc
        except OSError:
            if proc.poll() is not None:
                raise AssertionError(proc.log_path.read_text()) from None
            time.sleep(0.1)
    proc.kill()
    raise AssertionError("astiop serve did not start")


def stop_serve(proc) -> str:
    """SIGTERM, as Ctrl-C or systemd ends it; its log."""
    with contextlib.suppress(ProcessLookupError):
        proc.terminate()
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)
    return proc.log_path.read_text(errors="replace")


def descendants(pid: int) -> list[int]:
    """Every live process below `pid` (read from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if fields[0] != "Z":
            children.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def consoles_of(pid: int) -> list[int]:
    """The console processes under a server: `python -m astiop ...` with no subcommand."""
    out = []
    for child in descendants(pid):
        with contextlib.suppress(OSError):
            argv = Path(f"/proc/{child}/cmdline").read_bytes().split(b"\0")
            if b"astiop" in argv and b"estop" not in argv:
                out.append(child)
    return out


def wait_until(check, timeout: float = 20.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if check():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what or check}")


class Terminal:
    """A console's screen as the browser draws it: its websocket's bytes through pyte."""

    def __init__(self, width: int = 120, height: int = 40):
        self.closed = False  # its websocket closed (a reader that follows it says so)
        self.screen = pyte.Screen(width, height)
        self.stream = pyte.ByteStream(self.screen)

    def resize(self, width: int, height: int) -> None:
        self.screen.resize(height, width)

    def feed(self, data: bytes) -> None:
        self.stream.feed(data)

    def text(self) -> str:
        return "\n".join(line.rstrip() for line in self.screen.display)

    def has(self, pattern: str) -> bool:
        return re.search(pattern, self.text()) is not None
