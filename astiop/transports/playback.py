"""A recorded session's clock, the one capability only the replay transport has: declared here
as what a robot that plays back offers, not as an attribute every robot carries."""

from __future__ import annotations

from typing import Protocol, runtime_checkable


class Playback(Protocol):
    playing: bool
    speed: float

    @property
    def position_s(self) -> float: ...

    @property
    def duration_s(self) -> float: ...

    def toggle(self) -> bool: ...

    def step(self, seconds: float) -> None: ...

    def faster(self, up: bool) -> float: ...


@runtime_checkable
class PlaysBack(Protocol):
    """A robot that is a recording: it has a clock the operator moves."""

    playback: Playback
