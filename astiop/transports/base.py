"""What every robot backend offers the gateway: commands, live state, events, the map."""

from __future__ import annotations

import contextlib
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from contextlib import AbstractContextManager
from dataclasses import asdict, dataclass, field
from typing import Any, Union

from astiop.ros2.catalog import Catalog
from astiop.ros2.grammar import Ros2Command
from astiop.ros2.validation import Checked, always_allowed
from astiop.transports.errors import BackendError as BackendError  # raised by every transport
from astiop.transports.images import ImageMessage, image_message
from astiop.transports.inflight import InFlight, Job
from astiop.transports.state import OccupancyGrid, RobotEvent, RobotState, TopicStat
from astiop.warehouse import WarehouseMap

# A known layout (the simulator's warehouse), the robot's /map, or nothing: then the map view
# follows the robot and shows its scan.
MapGeometry = Union[WarehouseMap, OccupancyGrid, None]


@dataclass
class Execution:
    command: str
    valid: bool
    reason: str = ""
    kind: str = "read"
    executed: bool = False
    output: str = ""
    values: Any = None
    notes: list[str] = field(default_factory=list)
    error: str = ""
    duration_s: float = 0.0
    # measured (a reading the robot published), accepted (a service took a job on), commanded
    # (what astiop sent), or reported (any other answer of the robot)
    provenance: str = ""
    age_s: float | None = None  # a reading's age by its stamp, on the robot's clock
    period_s: float | None = None  # its topic's publishing period (None: latched or unknown)
    role: str = ""  # the role its name plays on the robot (ros2/profile.py): "battery", "pose"
    units: str | None = None  # battery: its profile's percentage scale (fraction | percent)

    def record(self) -> dict[str, Any]:
        """The fields a stored command row keeps."""
        return {
            "command": self.command,
            "valid": int(self.valid),
            "reason": self.reason or self.error or None,
            "kind": self.kind,
            "executed": int(self.executed),
            "output": self.output,
            "values": self.values,
            "provenance": self.provenance or None,
            "age_s": self.age_s,
        }

    def as_json(self) -> dict[str, Any]:
        keys = ("command", "valid", "reason", "kind", "executed", "output", "values")
        data = {k: v for k, v in asdict(self).items() if k in keys}
        if self.notes:
            data["notes"] = self.notes
        if self.error:
            data["error"] = self.error
        if self.provenance:
            data["provenance"] = self.provenance
        if self.age_s is not None:
            data["age_s"] = round(self.age_s, 3)
        return data


def command_of(checked: Checked) -> Ros2Command:
    """The command a transport runs: only a valid one reaches it, and a valid one has it."""
    return checked.parsed


def name_of(checked: Checked) -> str:
    """The topic, service, action or node the command names; BackendError if it names none."""
    return checked.named


def interface_of(checked: Checked) -> str:
    """The interface type validation resolved for the command (a message, service or action)."""
    return checked.interface


def message_of(checked: Checked) -> dict[str, Any]:
    """The checked values the command sends (its message, request or goal)."""
    return checked.values


def harmless(checked: Checked) -> bool:
    """A read, or a command that only makes the robot safer (a stop, a goal's cancel): it runs
    while the E-STOP holds, and asking it twice does no harm."""
    return checked.kind != "actuate" or always_allowed(checked)


def actuating(inflight: InFlight, checked: Checked) -> AbstractContextManager[Job | None]:
    """The job an actuating command runs as in `inflight` (refused while the E-STOP holds, ended
    by it); None for a read and for the stop itself, which must run while the E-STOP holds."""
    if harmless(checked):
        return contextlib.nullcontext(None)
    cmd = command_of(checked)
    return inflight.running(cmd.display(), cmd.name or "")


class RobotTransport(ABC):
    """The contract every transport's backend keeps (SimBackend, RclpyBackend, Ros2Backend,
    ReplayBackend): what the gateway and the app read, with the defaults of a live robot whose
    graph does not change. Each backend overrides what it has. (A verb runs on its backend's
    `verbs`, which keep ros2/verbs/transport.py's `Transport`.)"""

    name: str  # sim | ros2 | replay
    catalog: Catalog
    runs_commands: bool = True  # a replay runs none
    drives: bool = True  # teleop: a replay has none
    label: str = ""  # how the header names it, when `name` alone is not enough
    read_only: str = ""  # why commands are refused, when they are
    refreshed_at: float = 0.0  # time.monotonic() of the last read of the robot's graph
    refresh_every_s: float = 5.0  # a missing name reads the graph again at most this often
    params_wanted: bool = True  # the nodes' parameters read with the graph (finding a fleet: no)
    inflight: InFlight  # what this process has running that moves the robot

    def actuating(self, checked: Checked) -> AbstractContextManager[Job | None]:
        """The job an actuating command runs as (the E-STOP ends it); None for a read and for
        the stop itself, which must run while the E-STOP holds."""
        return actuating(self.inflight, checked)

    def zero_now(self) -> None:
        """A zero velocity at once where sending one is cheap (the E-STOP follows it)."""
        return None

    def watch_lightly(self, light: bool) -> None:
        """`light`: a fleet's robot watched for its row only (a live robot drops its scan)."""
        return None

    def refresh(self, settle: bool = True) -> bool:
        """Read the robot's graph again; False if nothing was read."""
        return False

    def control_channel(self, namespace: str):
        """Where the robot's lease is announced on its graph (robot/lease.py), for a robot that
        other machines reach too; None: the store alone holds it."""
        return None

    def warm_estop(self) -> None:
        """Make ready, in the background, what the E-STOP sends (nothing sent now)."""
        return None

    def robot_present(self) -> bool | None:
        """Whether any node other than astiop's stations is on the robot's graph now (None: not
        known to this transport)."""
        return None

    def estop_channel(self, namespace: str, on_word: Callable[[dict[str, Any]], None]):
        """Where the robot's E-STOP latch is announced on its graph (robot/station_latch.py):
        a channel with `announce(word)`, `settle()` (False: it ran out of time), `words()` and
        `close()`, calling `on_word` with each word heard; None: this transport cannot (the
        store alone holds it)."""
        return None

    def discovering(self) -> bool:
        """Whether this process may not have discovered the whole robot yet (a name missing
        from its graph may only not have been heard of)."""
        return False

    def robot_time(self) -> float | None:
        """Now on the clock the robot stamps its messages with (seconds), or None when it is
        not known here; a reading's age is measured on it."""
        return None

    def settle_estop(self, timeout_s: float) -> list[str]:
        """Wait (at most `timeout_s`) for what an E-STOP started in the background to go out, for
        a process about to exit; the failures that came. By default: the zero-Twist burst's
        second."""
        time.sleep(min(timeout_s, 1.0))
        return []

    def cancel_goals(self) -> None:
        """Cancel the goals this process sent and that still run (the live transports follow
        theirs; the simulator's goal yields to a zero velocity): nothing by default."""
        return None

    # -- the contract every backend keeps -----------------------------------------------------
    # Each failure that comes from the robot or the transport is raised as BackendError (with a
    # one-line reason) or, for the E-STOP's steps, returned as text: never another exception.

    @property
    @abstractmethod
    def e_stopped(self) -> bool:
        """Returns: whether the E-STOP holds in this process (nothing that moves starts)."""

    @abstractmethod
    def start(self) -> None:
        """Begin watching the robot (threads, subscriptions, streams); once, after __init__.

        Raises: BackendError if the robot cannot be reached at all."""

    @abstractmethod
    def close(self) -> None:
        """Stop every watch and cancel the goals this process sent; never raises."""

    @abstractmethod
    def estop(self) -> list[str]:
        """Hold first (nothing starts), end everything in flight, then stop the robot; no step
        waits for another, nothing raises.

        Returns: the failures of the steps taken so far (empty: all went out); a later one
        comes as an event (`settle_estop`)."""

    @abstractmethod
    def release_estop(self, *, robot: bool = True) -> list[str]:
        """Let the robot move again. Args: `robot=False`: this process only (another process
        released the latch and the robot).

        Returns: the failures (a robot that latches its own stop and did not answer its
        release); never raises."""

    @abstractmethod
    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        """Run one validated command. Args: `checked` (valid: validation/gateway made it),
        `timeout` in s for the robot's answer.

        Returns: (the text ros2 prints for it, the values astiop reads from it).
        Raises: BackendError: refused while the E-STOP holds (an actuation), ended by it, or
        failed on the robot (not served, timed out, refused)."""

    @abstractmethod
    def drive(self, twist: dict) -> None:
        """Teleop: hold this (already clamped) velocity for a short lapse time.

        Raises: BackendError: the E-STOP holds, or the robot has no velocity command."""

    @abstractmethod
    def state(self) -> RobotState:
        """Returns: the latest state; never blocks on the robot, never raises."""

    @abstractmethod
    def messages(self, names: Iterable[str]) -> dict[str, dict]:
        """Returns: the latest message on each of these topics that has one, as the robot sent
        it (a topic with none is left out)."""

    @abstractmethod
    def message_times(self, names: Iterable[str]) -> dict[str, float]:
        """Returns: when each of those latest messages came, on the robot's clock
        (`RobotState.t`): published (simulator), received (robot), logged (replay)."""

    @abstractmethod
    def events_since(self, seq: int) -> list[RobotEvent]:
        """Returns: the events numbered after `seq`, oldest first (a bounded history)."""

    @abstractmethod
    def topic_stats(self) -> list[TopicStat]:
        """Returns: each watched topic's expected and measured rate and its last message's
        age."""

    @abstractmethod
    def wait_until_idle(self, timeout_s: float) -> str | None:
        """Block, at most `timeout_s`, until the robot has no active goal.

        Returns: how the goal ended ("succeeded", "canceled", ...), None if not known or
        still running."""

    @abstractmethod
    def map_geometry(self) -> MapGeometry:
        """Returns: the map as known now (never read here): the warehouse, the robot's /map,
        or None."""

    def image(self, name: str) -> ImageMessage | None:
        """The latest message on the image topic `name` (its pixels as bytes), or None when
        none came; ValueError when it is no image. By default from `messages()`."""
        msg = self.messages([name]).get(name)
        if msg is None:
            return None
        return image_message(name, msg, self.message_times([name]).get(name))

    def read_map(self, timeout_s: float) -> MapGeometry:
        """The robot's map, read now if it has not been (a one-shot command never started the
        watch that reads it): a goal's geofence may be its extent."""
        return self.map_geometry()
