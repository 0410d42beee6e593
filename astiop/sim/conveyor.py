"""The conveyor module: a belt, two load sensors (entry and seated) and a transfer timer."""

from __future__ import annotations

from dataclasses import dataclass

TRANSFER_S = 4.0


@dataclass
class Conveyor:
    loaded: bool = False
    direction: int = 0  # +1 loading, -1 unloading, 0 stopped
    elapsed: float = 0.0
    transfers: int = 0

    @property
    def running(self) -> bool:
        return self.direction != 0

    @property
    def sensor_entry(self) -> bool:
        # the load passes the entry sensor during the middle of a transfer
        return self.running and 0.25 * TRANSFER_S <= self.elapsed <= 0.75 * TRANSFER_S

    @property
    def sensor_seated(self) -> bool:
        if self.direction > 0:
            return self.elapsed > 0.75 * TRANSFER_S
        if self.direction < 0:
            return self.elapsed < 0.25 * TRANSFER_S
        return self.loaded

    def start(self, direction: int) -> None:
        self.direction, self.elapsed = direction, 0.0

    def update(self, dt: float) -> str | None:
        """Advance a running transfer; returns 'loaded'/'unloaded' when one completes."""
        if not self.running:
            return None
        self.elapsed += dt
        if self.elapsed < TRANSFER_S:
            return None
        done = "loaded" if self.direction > 0 else "unloaded"
        self.loaded = self.direction > 0
        self.direction, self.elapsed = 0, 0.0
        self.transfers += 1
        return done

    def abort(self) -> None:
        self.direction, self.elapsed = 0, 0.0
