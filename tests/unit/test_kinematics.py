"""Mecanum kinematics against the paper's equations (Eq. 3-6) and Figure 3's motion patterns."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from astiop.sim.kinematics import (
    ASTIBOT,
    MecanumParams,
    achievable_velocity,
    forward_kinematics,
    forward_matrix,
    inverse_kinematics,
    inverse_matrix,
    saturate_wheels,
)


def test_pseudo_inverse_pair_gives_identity():
    T, Tp = forward_matrix(), inverse_matrix()
    np.testing.assert_allclose(T @ Tp, np.eye(3), atol=1e-12)
    # and T⁺ is the Moore-Penrose pseudo-inverse of T (Eq. 4-5)
    np.testing.assert_allclose(np.linalg.pinv(T), Tp, atol=1e-9)


def test_functions_match_matrices():
    u = np.array([0.3, -0.2, 0.4])
    np.testing.assert_allclose(inverse_kinematics(*u), inverse_matrix() @ u, atol=1e-12)
    w = np.array([1.0, -2.0, 3.0, 0.5])
    np.testing.assert_allclose(forward_kinematics(w), forward_matrix() @ w, atol=1e-12)


@pytest.mark.parametrize(
    "u,signs",
    [
        ((0.5, 0, 0), [1, 1, 1, 1]),  # forward: all wheels forward
        ((-0.5, 0, 0), [-1, -1, -1, -1]),
        ((0, 0.5, 0), [-1, 1, 1, -1]),  # sideways left: FL, RR back; FR, RL forward
        ((0, -0.5, 0), [1, -1, -1, 1]),
        ((0.5, 0.5, 0), [0, 1, 1, 0]),  # diagonal front-left: FR and RL only
        ((0.5, -0.5, 0), [1, 0, 0, 1]),  # diagonal front-right: FL and RR only
        ((0, 0, 1.0), [-1, 1, -1, 1]),  # turn left in place: left side back, right forward
        ((0, 0, -1.0), [1, -1, 1, -1]),
    ],
)
def test_figure_3_motion_patterns(u, signs):
    w = inverse_kinematics(*u)
    assert list(np.sign(np.round(w, 12)).astype(int)) == signs


def test_physical_units():
    # 1 m/s forward spins a 76.2 mm wheel at 1/r rad/s
    np.testing.assert_allclose(inverse_kinematics(1.0, 0, 0), [1 / 0.0762] * 4)
    assert ASTIBOT.max_wheel_speed * ASTIBOT.wheel_radius == pytest.approx(1.3965, abs=1e-3)


@given(
    st.floats(-2, 2),
    st.floats(-2, 2),
    st.floats(-3, 3),
    st.floats(0.1, 0.6),
    st.floats(0.1, 0.6),
    st.floats(0.03, 0.2),
)
def test_round_trip(vx, vy, wz, lx, ly, r):
    p = MecanumParams(lx=lx, ly=ly, wheel_radius=r)
    back = forward_kinematics(inverse_kinematics(vx, vy, wz, p), p)
    np.testing.assert_allclose(back, [vx, vy, wz], atol=1e-9)


@given(st.floats(-5, 5), st.floats(-5, 5), st.floats(-5, 5))
def test_saturation_keeps_direction(vx, vy, wz):
    w = inverse_kinematics(vx, vy, wz)
    ws, scale = saturate_wheels(w)
    assert np.max(np.abs(ws)) <= ASTIBOT.max_wheel_speed + 1e-9
    np.testing.assert_allclose(ws, w * scale, atol=1e-12)
    u = forward_kinematics(ws)
    np.testing.assert_allclose(u, np.array([vx, vy, wz]) * scale, atol=1e-9)
    np.testing.assert_allclose(achievable_velocity(vx, vy, wz), u, atol=1e-9)
