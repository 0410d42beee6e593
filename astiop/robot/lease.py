"""One operator in control of a shared robot: the lease. A console (or the MCP server, or a
one-shot command) takes a robot's lease to actuate it; another process on the same database
sees it held and actuates nothing until it takes it over. The gateway asks the lease before any
motion; a stop (zero velocity, /stop, a goal's cancel) needs none: anyone may stop any robot.

Only a robot reached over ROS 2 is shared: the in-process simulator is each console's own.
The lease is keyed by the robot's namespace ("/" un-namespaced) and domain."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import uuid
from dataclasses import dataclass

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

    @property
    def words(self) -> str:
        return f"{self.who} (pid {self.pid} on {self.host})"


def _holder(row: dict) -> Holder:
    return Holder(row["who"], row["host"], int(row["pid"]), float(row["taken_at"]))


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
    when another process took it over (`on_lost(holder)`, from the heartbeat's thread)."""

    def __init__(self, store: Store, robot: str, name: str, who: str = "astiop"):
        self.store, self.robot, self.name, self.who = store, robot, name, who
        self.token = uuid.uuid4().hex
        self.host, self.pid = socket.gethostname(), os.getpid()
        self.on_lost = lambda holder: None
        self._held = False
        self._halt = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def held(self) -> bool:
        return self._held

    def holder(self) -> Holder | None:
        """Who controls the robot now (None: no one)."""
        row = self.store.lease(self.robot)
        return _holder(row) if row else None

    def other_holder(self) -> Holder | None:
        row = self.store.lease(self.robot)
        return _holder(row) if row and row["token"] != self.token else None

    def take(self, force: bool = False) -> Holder | None:
        """Take control; the live holder that refused it (None: taken)."""
        refused = self.store.take_lease(
            self.robot, self.token, self.who, self.host, self.pid, force
        )
        self._held = refused is None
        if self._held:
            self._start_heartbeat()
        return _holder(refused) if refused else None

    def refusal(self, checked: Checked) -> str | None:
        """Why this actuation may not run here (None: it may)."""
        if checked.kind != "actuate" or is_stop(checked):
            return None
        row = self.store.lease(self.robot)  # a read: another may have taken it a moment ago
        if self._held and row is not None and row["token"] == self.token:
            return None
        self._held = False
        if row is not None and row["token"] != self.token:
            other = _holder(row)
            return (
                f"{self.name} is controlled by {other.words}: take control of it first "
                "(the console's ctrl+t, or --take)"
            )
        return f"{self.name} is not controlled from here: take control of it first"

    def _start_heartbeat(self) -> None:
        if self._thread is None or not self._thread.is_alive():
            self._halt.clear()
            self._thread = threading.Thread(target=self._beat, name="lease", daemon=True)
            self._thread.start()

    def _beat(self) -> None:
        while not self._halt.wait(HEARTBEAT_S):
            try:
                kept = self.store.renew_lease(self.robot, self.token)
            except Exception:  # noqa: BLE001 - a busy store: tried again at the next beat
                continue
            if not kept and self._held:
                self._held = False
                self.on_lost(self.other_holder())
                return

    def release(self) -> None:
        self._halt.set()
        if self._held:
            self._held = False
            with contextlib.suppress(Exception):  # it expires by itself
                self.store.release_lease(self.robot, self.token)
