"""The robot state the console reads is what the robot's own messages say (sim ground truth)."""

import math

import pytest

from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.state import from_messages


def test_state_from_messages_agrees_with_the_simulator():
    sim = Simulator(seed=0)
    sim.add_obstacle("pallet", 16.0, 8.75)
    sim.goto(37.6, 21.0, 0.0, "cps_storage")
    for seconds in (12.0, 5.0, 10.0):
        sim.step(seconds)
        truth, st = sim.snapshot(), SimBackend(sim).state()
        assert (st.pose.x, st.pose.y) == pytest.approx((truth.x, truth.y), abs=1e-3)
        assert st.battery.percentage == pytest.approx(truth.battery_soc, abs=1e-5)
        assert st.status.state == truth.state and st.status.active_goal == "cps_storage"
        assert st.distance_remaining == pytest.approx(truth.distance_remaining, abs=0.01)
        assert len(st.scan.ranges) == 360 and st.speed == pytest.approx(truth.speed, abs=1e-6)


def test_absent_topics_stay_absent():
    st = from_messages(1.0, {"/robot_status": {"state": "idle"}})
    assert st.pose is None and st.battery is None and st.scan is None and st.obstacles is None
    assert st.status.state == "idle" and st.distance_remaining is None


def test_odometry_stands_in_for_a_missing_pose():
    yaw = 0.5
    odom = {
        "pose": {
            "pose": {
                "position": {"x": 2.0, "y": 3.0},
                "orientation": {"z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
            }
        },
        "twist": {"twist": {"linear": {"x": 0.4, "y": 0.0}, "angular": {"z": 0.0}}},
    }
    st = from_messages(0.0, {"/odom": odom})
    assert (st.pose.x, st.pose.y, st.pose.theta) == pytest.approx((2.0, 3.0, yaw))
    assert st.wheel_speeds[0] == pytest.approx(st.wheel_speeds[1])  # straight ahead
