"""One emulated `ros2` call: what it prints, how it ends, and SIGINT from its client."""

from __future__ import annotations

import contextlib
import json
import socket
import threading


class Interrupted(Exception):
    """The client got SIGINT, or went away."""


class Call:
    """One client connection: output goes back as JSON lines; SIGINT arrives as a line."""

    def __init__(self, conn: socket.socket):
        self.conn = conn
        self.reader = conn.makefile("r", encoding="utf-8")
        self.interrupted = threading.Event()
        self.request = json.loads(self.reader.readline() or "{}")
        threading.Thread(target=self._watch, daemon=True).start()

    def _watch(self) -> None:
        try:
            for _line in self.reader:
                self.interrupted.set()
        except (OSError, ValueError):
            pass
        self.interrupted.set()  # the client is gone: stop as on SIGINT

    def _send(self, msg: dict) -> None:
        try:
            self.conn.sendall((json.dumps(msg) + "\n").encode())
        except OSError:
            self.interrupted.set()
            raise Interrupted from None

    def out(self, text: str) -> None:
        self._send({"out": text})

    def err(self, text: str) -> None:
        self._send({"err": text})

    def wait(self, seconds: float) -> None:
        if self.interrupted.wait(seconds):
            raise Interrupted

    def finish(self, code: int) -> None:
        with contextlib.suppress(Interrupted):
            self._send({"exit": code})
        with contextlib.suppress(OSError):  # the reader's file object holds it open
            self.conn.shutdown(socket.SHUT_RDWR)
        self.conn.close()
