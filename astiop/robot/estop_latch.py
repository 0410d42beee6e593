"""The gateway's E-STOP, latched in the store: every astiop process on that database refuses
actuation while it holds, and a restart keeps it."""

from __future__ import annotations

import contextlib
import logging
import threading
from typing import TYPE_CHECKING, Protocol

from astiop.robot.safety import always_allowed
from astiop.ros2.validation import Checked
from astiop.store import Store
from astiop.transports.base import RobotBackend

log = logging.getLogger("astiop.robot")
HELD_FOR_ALL = (
    "the E-STOP of every robot on this database still holds it: astiop estop --release --all"
)
ESTOP_REASON = "the E-STOP is engaged: no motion command runs until the operator releases it"


class LatchHost(Protocol):
    """What `EstopLatch` needs of the gateway it is mixed into."""

    backend: RobotBackend
    store: Store | None
    who: str
    latch_key: str
    _latch_seen: bool
    _latch_lock: threading.Lock


if TYPE_CHECKING:
    _Host = LatchHost
else:
    _Host = object


class EstopLatch(_Host):
    @property
    def latched(self) -> bool:
        """The store's latch: every robot's, or this robot's own."""
        store = self.store
        if store is None:
            return False
        own = self.latch_key and store.robot_latch(self.latch_key) is not None
        return bool(own) or store.estop_latch() is not None

    @property
    def e_stopped(self) -> bool:
        return self.backend.e_stopped or self.latched

    def estop(self) -> list[str]:
        """Stop the robot, then latch it for every process; returns steps that failed."""
        failures = self.backend.estop()  # the robot first: the record must never delay it
        if self.store is not None:
            try:
                with self._latch_lock:  # the sampler's follow_latch must not undo it
                    if self.latch_key:
                        self.store.latch_robot(self.latch_key, self.who)
                    else:
                        self.store.latch_estop(self.who)
                    self._latch_seen = True
            except Exception as exc:  # noqa: BLE001 - reported, the stop itself went out
                failures.append(f"the E-STOP is not latched for other processes: {exc}")
        return failures

    def zero_now(self) -> None:
        """A zero velocity sent at once, nothing else (a fleet's E-STOP sends every robot's
        before the rest of each one's stop); never raises: the E-STOP that follows says why."""
        with contextlib.suppress(Exception):
            self.backend.zero_now()

    def settle_estop(self, timeout_s: float) -> list[str]:
        """Wait for what the E-STOP started in the background to go out (a process about to
        exit); the failures that came meanwhile."""
        return self.backend.settle_estop(timeout_s)

    def release_estop(self) -> list[str]:
        """Release the latch for every process, then this process's robot; the failures. A
        fleet's robot releases its own latch; one on every robot still holds it."""
        if self.store is not None:
            with self._latch_lock:
                if self.latch_key:
                    self.store.release_robot(self.latch_key)
                    if self.store.estop_latch() is not None:
                        return [HELD_FOR_ALL]
                else:
                    self.store.release_estop(self.who)
                self._latch_seen = False
        return self.backend.release_estop()

    def follow_latch(self) -> bool:
        """Whether the E-STOP is latched; when another process (a second console, `astiop
        estop`) latched or released it since the last look, this process's robot follows."""
        if self.store is None:
            return False
        with self._latch_lock:  # read and acted on together: an estop() meanwhile waits
            latched = self.latched
            if latched != self._latch_seen:
                self._latch_seen = latched
                if latched and not self.backend.e_stopped:
                    self.backend.estop()
                elif not latched and self.backend.e_stopped:
                    self.backend.release_estop(robot=False)  # the releaser told the robot
            if not latched:
                self._end_what_moves_latched_robots()
        return latched

    def _end_what_moves_latched_robots(self) -> None:
        """What this process has in flight on another robot of the fleet, reached by its names,
        ends when that robot's own E-STOP latches (in any process)."""
        inflight = self.backend.inflight
        if not inflight.busy:
            return
        latched = self._latched_robots()
        if latched:
            ended = inflight.end_where(lambda name: any(_under(name, ns) for ns in latched))
            for failure in ended:
                log.error(failure)

    def _held_by_estop(self, checked: Checked) -> bool:
        """Latched (this robot, or the fleet's robot the command is sent to), and not a command
        the E-STOP always lets through (/stop)."""
        if always_allowed(checked):
            return False
        if self.e_stopped:
            return True
        name = checked.command.name if checked.command else None
        return bool(name) and any(_under(name, ns) for ns in self._latched_robots())

    def _latched_robots(self) -> list[str]:
        """The namespaces of every robot whose own E-STOP is latched (none without a store)."""
        return self.store.latched_robots() if self.store is not None else []


def _under(name: str, namespace: str) -> bool:
    """Whether `name` is inside `namespace` ("/tb3_1/cmd_vel" is inside "/tb3_1")."""
    return name.startswith(namespace.rstrip("/") + "/")
