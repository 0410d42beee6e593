"""One operator in control of a shared robot: the lease. A console (or the MCP server, or a
one-shot command) takes a robot's lease to actuate it; another process sees it held and
actuates nothing until it takes it over. The gateway asks the lease before any motion; a stop
(zero velocity, /stop, a goal's cancel) needs none: anyone may stop any robot.

It holds between processes on one machine through the store (one row per robot, taken in one
write), and between machines on one ROS 2 domain through the robot's graph where the transport
can announce it (rclpy: transports/rclpy/control_topic.py). Of two holders the latest take wins:
a takeover is a take made later. Only a robot reached over ROS 2 is shared: the in-process
simulator is each console's own. A robot is keyed by its namespace and domain."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from astiop.robot.safety import always_allowed
from astiop.ros2.validation import Checked
from astiop.store import Store

HEARTBEAT_S = 2.0


@dataclass(frozen=True)
class Holder:
    who: str
    host: str
    pid: int
    taken_at: float
    token: str = ""

    @property
    def words(self) -> str:
        return f"{self.who} (pid {self.pid} on {self.host})"


def _holder(row: dict) -> Holder:
    return Holder(
        str(row["who"]), str(row["host"]), int(row["pid"]), float(row["taken_at"]),
        str(row.get("token", "")),
    )  # fmt: skip


def is_stop(checked: Checked) -> bool:
    """A command that only ever stops: the stop service, a goal's cancel, zero velocity."""
    if always_allowed(checked):
        return True
    cmd, message = checked.command, checked.message
    if cmd is None or cmd.key != ("topic", "pub") or not isinstance(message, dict):
        return False
    twist = message.get("twist", message)
    parts = [twist.get("linear"), twist.get("angular")]
    values = [v for p in parts if isinstance(p, dict) for v in p.values()]
    return bool(values) and all(isinstance(v, (int, float)) and v == 0 for v in values)


def lease_key(namespace: str, domain: int | str | None) -> str:
    return f"{namespace or '/'}@{domain if domain not in (None, '') else 0}"


class Lease:
    """This process's hold on one robot: `take()` (refused while another live holder has it,
    unless `force`), `refusal(checked)` for the gateway, a heartbeat that renews it and notices
    when another process took it over (`on_lost(holder)`, from the heartbeat's thread).
    `channel()`: the robot's graph to announce it on (None: the store alone)."""

    def __init__(
        self,
        store: Store,
        robot: str,
        name: str,
        who: str = "astiop",
        channel: Callable[[], Any] | None = None,
    ):
        self.store, self.robot, self.name, self.who = store, robot, name, who
        self.token = uuid.uuid4().hex
        self.host, self.pid = socket.gethostname(), os.getpid()
        self.on_lost: Callable[[Holder | None], None] = lambda holder: None
        self._open_channel = channel
        self._channel: Any = None
        self._closed = False  # released for good: a take still under way takes nothing
        self._held = False
        self.tried = False  # a take was answered (held or refused) at least once
        self._taken_at = 0.0
        self._halt = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def held(self) -> bool:
        return self._held

    @property
    def channel(self) -> Any:
        """The robot's graph, opened the first time it is needed."""
        if self._channel is None and self._open_channel is not None and not self._closed:
            self._channel = self._open_channel()
            self._open_channel = None
            if self._closed:  # released while it was being opened: its word is never said
                with contextlib.suppress(Exception):
                    self._channel.close()
            elif not self._held:  # every writer says a word: a take waits for no silent one
                self._announce(released=True)
        return self._channel

    def _remote(self, released: bool = False) -> list[Holder]:
        """Live holders announced on the robot's graph, other than this one, latest first
        (`released`: with those that let go since)."""
        channel = self.channel
        words = channel.holders(released) if channel is not None else []
        return [_holder(w) for w in words if w.get("token") != self.token]

    def holder(self) -> Holder | None:
        """Who controls the robot now (None: no one): the latest live take."""
        row = self.store.lease(self.robot)
        found = [_holder(row)] if row else []
        found += self._remote()
        return max(found, key=lambda h: (h.taken_at, h.token)) if found else None

    def other_holder(self) -> Holder | None:
        holder = self.holder()
        return holder if holder is not None and holder.token != self.token else None

    def take(self, force: bool = False) -> Holder | None:
        """Take control; the live holder that refused it (None: taken)."""
        try:
            if not force and (remote := self._remote()):
                return remote[0]
            if self._closed:
                return None  # released meanwhile (a console closing): nothing to take
            refused = self.store.take_lease(
                self.robot, self.token, self.who, self.host, self.pid, force
            )
            if refused is None and self._closed:  # released while it was being taken
                with contextlib.suppress(Exception):
                    self.store.release_lease(self.robot, self.token)
                return None
            self._held = refused is None
            if self._held:
                self._taken_at = time.time()
                # a takeover reaches the one it took from
                self._announce(acked_s=1.0 if force else 0.0)
                self._start_heartbeat()
            return _holder(refused) if refused else None
        finally:
            self.tried = True

    def _announce(self, released: bool = False, acked_s: float = 0.0) -> None:
        channel = self.channel
        if channel is None:
            return
        with contextlib.suppress(Exception):  # the store still holds it on this machine
            channel.announce({
                "token": self.token, "who": self.who, "host": self.host, "pid": self.pid,
                "taken_at": self._taken_at, "released": released,
            }, acked_s)  # fmt: skip

    def _overtaken(self) -> Holder | None:
        """A holder elsewhere that took the robot after this process did (and may have let go
        of it since: control was taken from this process all the same)."""
        later = [
            h
            for h in self._remote(released=True)
            if (h.taken_at, h.token) > (self._taken_at, self.token)
        ]
        return later[0] if later else None

    def refusal(self, checked: Checked) -> str | None:
        """Why this actuation may not run here (None: it may). A robot no one controls is
        taken here by the first motion sent to it."""
        if checked.kind != "actuate" or is_stop(checked):
            return None
        row = self.store.lease(self.robot)  # a read: another may have taken it a moment ago
        ours = self._held and row is not None and row["token"] == self.token
        if ours and self._overtaken() is None:
            return None
        self._held = False
        other = self.take()
        if other is None:
            return None
        return (
            f"{self.name} is controlled by {other.words}: take control of it first "
            "(the console's ctrl+t, or --take)"
        )

    def _start_heartbeat(self) -> None:
        if self._closed:
            return
        if self._thread is None or not self._thread.is_alive():
            self._halt.clear()
            self._thread = threading.Thread(target=self._beat, name="lease", daemon=True)
            self._thread.start()

    def _beat(self) -> None:
        while not self._halt.wait(HEARTBEAT_S) and not self._closed:
            try:
                kept = self.store.renew_lease(self.robot, self.token)
            except Exception:  # noqa: BLE001 - a busy store: tried again at the next beat
                continue
            overtaken = self._overtaken()
            if kept and overtaken is None:
                self._announce()
                continue
            if self._held:
                self._held = False
                if kept:  # taken on another machine: the store's row is let go here
                    with contextlib.suppress(Exception):
                        self.store.release_lease(self.robot, self.token)
                self.on_lost(overtaken or self.other_holder())
            return

    def let_go(self) -> None:
        """Control given up: the robot is free for anyone to take; this process watches it (and
        takes it again with its next motion if no one has)."""
        self._halt.set()
        beat = self._thread
        if beat is not None and beat is not threading.current_thread():
            beat.join(HEARTBEAT_S)  # its last renewal must not follow the letting go
        if self._held:
            self._held = False
            self._announce(released=True, acked_s=0.5)
            with contextlib.suppress(Exception):  # it expires by itself
                self.store.release_lease(self.robot, self.token)

    def release(self) -> None:
        """Let go for good (this process is done with the robot): a take under way on another
        thread takes nothing, and nothing but its letting go is said on the robot's graph."""
        self._closed = True
        self.let_go()
        if self._channel is not None:
            with contextlib.suppress(Exception):
                self._channel.close()
