"""What every robot backend offers the gateway: commands, live state, events, the map."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol, Union

from astiop.robot.state import OccupancyGrid, RobotEvent, RobotState, TopicStat
from astiop.ros2.catalog import Catalog
from astiop.ros2.validation import Checked
from astiop.warehouse import WarehouseMap

# A known layout (the simulator's warehouse), the robot's /map, or nothing: then the map view
# follows the robot and shows its scan.
MapGeometry = Union[WarehouseMap, OccupancyGrid, None]


class BackendError(Exception):
    """The command was valid but running it failed (timeout, no message, process error)."""


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
        }

    def as_json(self) -> dict[str, Any]:
        keys = ("command", "valid", "reason", "kind", "executed", "output", "values")
        data = {k: v for k, v in asdict(self).items() if k in keys}
        if self.notes:
            data["notes"] = self.notes
        if self.error:
            data["error"] = self.error
        return data


class RobotBackend(Protocol):
    name: str  # sim | ros2 | replay
    catalog: Catalog
    capabilities: frozenset[str]  # "commands", "teleop"; a replay has neither

    @property
    def e_stopped(self) -> bool: ...

    def start(self) -> None: ...

    def close(self) -> None: ...

    def estop(self) -> list[str]:
        """Stop the robot now; returns the failures of each step (empty: all went out)."""
        ...

    def release_estop(self) -> None: ...

    def execute(self, checked: Checked, timeout: float) -> tuple[str, object]: ...

    def drive(self, twist: dict) -> None:
        """Teleop: hold this (already clamped) velocity for a short lapse time."""
        ...

    def state(self) -> RobotState:
        """The latest state; never blocks on the robot."""
        ...

    def messages(self, names: Iterable[str]) -> dict[str, dict]:
        """The latest message on each of these topics that has one, as the robot sent it."""
        ...

    def message_times(self, names: Iterable[str]) -> dict[str, float]:
        """When each of those latest messages came, on the robot's clock (`RobotState.t`):
        published (simulator), received (robot), logged (replay)."""
        ...

    def events_since(self, seq: int) -> list[RobotEvent]: ...

    def topic_stats(self) -> list[TopicStat]: ...

    def wait_until_idle(self, timeout_s: float) -> str | None:
        """Block until the robot has no active goal; returns how the goal ended, if known."""
        ...

    def map_geometry(self) -> MapGeometry: ...
