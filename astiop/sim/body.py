"""The base's body: its footprint, mass, drive and the load its motors put on the battery.

The ASTIbot is a holonomic mecanum base; a differential base (a TurtleBot3) is the same wheel
model with the lateral velocity held at zero and lx = 0, so u = (r/4)·T·w gives its two wheel
speeds (v ∓ (b/2)·ω)/r twice over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from astiop.sim.kinematics import ASTIBOT, MecanumParams


@dataclass(frozen=True)
class Body:
    length: float  # m, along x
    width: float  # m, along y
    mass: float  # kg
    wheels: MecanumParams = ASTIBOT
    differential: bool = False  # no lateral motion: vy is always 0
    wheel_torque_nm: float = 0.34  # rolling resistance at each wheel
    idle_w: float = 2.0  # draw of each turning motor
    efficiency: float = 0.75

    @property
    def inflation(self) -> float:
        """How far the planner keeps the base's centre from fixed geometry: its circumscribed
        radius and a margin."""
        return math.hypot(self.length, self.width) / 2 + 0.1

    def motor_power(self, wheel_speeds) -> float:
        """W drawn by the drive at these wheel speeds (rad/s)."""
        turning, rolling, torque = 0, 0, self.wheel_torque_nm
        for w in wheel_speeds:  # a loop, not two generators: 20 Hz; the same sums in order
            w = abs(w)
            turning += w > 0.05
            rolling += torque * w
        return (rolling + self.idle_w * turning) / self.efficiency


ASTIBOT_BODY = Body(length=1.0, width=0.735, mass=45.0)
