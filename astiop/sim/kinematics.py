"""Mecanum kinematics of the ASTIbot in physical units (paper Eq. 3-6).

Body velocity u = [vx, vy, wz] (x forward, y left), wheel speeds w = [FL, FR, RL, RR] in rad/s,
roller angles -45°, 45°, 45°, -45° (Table 4). The paper sets r = 1 and drops T's 1/4; here
u = (r/4)·T·w and w = (1/r)·T⁺·u with k = lx + ly, so T·T⁺ = I₃ holds in physical units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MecanumParams:
    lx: float = 0.25  # half the wheelbase, m
    ly: float = 0.2925  # half the track, m
    wheel_radius: float = 0.0762  # 152.4 mm wheels
    max_wheel_rpm: float = 175.0  # MD60 rated speed at the wheel

    @property
    def k(self) -> float:
        return self.lx + self.ly

    @property
    def max_wheel_speed(self) -> float:
        """rad/s at the motor limit (18.3 rad/s; 1.40 m/s at the rim)."""
        return self.max_wheel_rpm * 2.0 * math.pi / 60.0


ASTIBOT = MecanumParams()


def forward_matrix(params: MecanumParams = ASTIBOT) -> np.ndarray:
    """T (3×4): u = T·w."""
    k = params.k
    return (params.wheel_radius / 4.0) * np.array(
        [[1.0, 1.0, 1.0, 1.0], [-1.0, 1.0, 1.0, -1.0], [-1.0 / k, 1.0 / k, -1.0 / k, 1.0 / k]]
    )


def inverse_matrix(params: MecanumParams = ASTIBOT) -> np.ndarray:
    """T⁺ (4×3): w = T⁺·u."""
    k = params.k
    return (1.0 / params.wheel_radius) * np.array(
        [[1.0, -1.0, -k], [1.0, 1.0, k], [1.0, 1.0, -k], [1.0, -1.0, k]]
    )


def inverse_kinematics(
    vx: float, vy: float, wz: float, params: MecanumParams | None = None
) -> np.ndarray:
    """Wheel speeds (rad/s, FL FR RL RR) for a body velocity; not saturated."""
    return np.array(wheel_speeds(vx, vy, wz, params))


def wheel_speeds(
    vx: float, vy: float, wz: float, params: MecanumParams | None = None
) -> tuple[float, float, float, float]:
    """`inverse_kinematics` as a tuple of floats (the simulator's 20 Hz control needs no array)."""
    p = params or ASTIBOT
    k, r = p.k, p.wheel_radius
    return (
        (vx - vy - k * wz) / r,
        (vx + vy + k * wz) / r,
        (vx + vy - k * wz) / r,
        (vx - vy + k * wz) / r,
    )


def forward_kinematics(w, params: MecanumParams | None = None) -> np.ndarray:
    """Body velocity (vx, vy, wz) from the four wheel speeds."""
    p = params or ASTIBOT
    w1, w2, w3, w4 = (float(v) for v in w)
    r, k = p.wheel_radius, p.k
    return np.array(
        [
            r / 4 * (w1 + w2 + w3 + w4),
            r / 4 * (-w1 + w2 + w3 - w4),
            r / (4 * k) * (-w1 + w2 - w3 + w4),
        ]
    )


def saturate_wheels(w: np.ndarray, params: MecanumParams | None = None) -> tuple[np.ndarray, float]:
    """Scale all four wheels together to the motor limit; returns (w, scale <= 1)."""
    p = params or ASTIBOT
    peak = float(np.max(np.abs(w)))
    if peak <= p.max_wheel_speed:
        return w, 1.0
    scale = p.max_wheel_speed / peak
    return w * scale, scale


def achievable_velocity(
    vx: float, vy: float, wz: float, params: MecanumParams | None = None
) -> tuple[float, float, float]:
    """The body velocity the wheels can actually give for a command, direction kept."""
    p = params or ASTIBOT
    k, r, limit = p.k, p.wheel_radius, p.max_wheel_speed
    peak = (abs(vx) + abs(vy) + k * abs(wz)) / r  # max |w_i| of the inverse kinematics
    if peak <= limit:
        return vx, vy, wz
    s = limit / peak
    return vx * s, vy * s, wz * s
