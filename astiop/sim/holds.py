"""What keeps the base from moving: its E-STOP input, a latched /stop, a collision fault."""

from __future__ import annotations

from dataclasses import dataclass

from astiop.sim.goal import GoalError

STOP_LATCHED = "the stop is latched: /release to move again"


@dataclass
class Holds:
    e_stopped: bool = False  # the robot's E-STOP input
    stop_latched: bool = False  # /stop holds the base, as a safety controller does
    fault: str = ""  # a collision, until /stop acknowledges it

    @property
    def held(self) -> bool:
        """Whether the base holds still until /release: its E-STOP input, or a latched /stop."""
        return self.e_stopped or self.stop_latched

    def check_can_move(self) -> None:
        """Raise GoalError, saying why, unless a motion command may start now."""
        if self.e_stopped:
            raise GoalError("the robot is e-stopped; release the e-stop first")
        if self.stop_latched:
            raise GoalError(STOP_LATCHED)
        if self.fault:
            raise GoalError(f"the robot has a fault ({self.fault}); call /stop to acknowledge it")
