"""Missions on a real ROS 2 robot (`astiop sim node` over DDS, through rclpy) and on the emulated
robot behind the `ros2` executable: the steps in order, each ended as the robot reported it."""

from __future__ import annotations

import math

import pytest

from astiop.missions import view
from astiop.missions.runner import MissionRunner
from astiop.missions.steps import Step
from astiop.robot.factory import make_robot_gateway
from astiop.store import Store
from tests.emulator import emulated_robot, on_path
from tests.ros import require_ros, sim_node, whole_robot
from tests.ros.test_ros2_emulated import make_gateway
from tests.ros.test_ros2_rclpy import settings

pytestmark = pytest.mark.slow
STEPS = [Step("undock"), Step("goto", place="inspection_zone_a"), Step("dock")]


def check_in_order(store: Store, mission_id: int, gateway) -> None:
    m = view.as_json(store, mission_id)
    assert m["status"] == "succeeded", m
    steps = m["steps"]
    assert [s["status"] for s in steps] == ["succeeded"] * 3
    zone = store.get_location("inspection_zone_a")
    pose = steps[1]["pose"]
    assert math.dist((pose["x"], pose["y"]), (zone.x, zone.y)) <= 0.3, steps[1]
    assert steps[0]["docked"] is False and steps[2]["docked"] is True
    assert steps[0]["ended_at"] <= steps[1]["started_at"] <= steps[1]["ended_at"]
    assert steps[1]["ended_at"] <= steps[2]["started_at"]
    # the robot's own report at the end agrees with the stored one
    echo = gateway.run("ros2 topic echo /robot_status --once").values
    assert echo["docked"] in (True, 1), echo


@pytest.mark.ros
def test_a_mission_on_sim_node_over_dds(tmp_path):
    require_ros()
    with sim_node(speed=8.0):
        store = Store(tmp_path / "rclpy.db")
        gateway = make_robot_gateway(settings(tmp_path), store)
        gateway.start()
        try:
            whole_robot(gateway)
            runner = MissionRunner(gateway, store, step_timeout_s=120)
            mission_id = runner.start(STEPS, "over dds")
            assert runner.wait(240)
            check_in_order(store, mission_id, gateway)
        finally:
            gateway.close()
            store.close()


def test_a_mission_on_the_emulated_cli_robot(tmp_path, monkeypatch):
    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        store = Store(tmp_path / "cli.db")
        gateway = make_gateway(store)
        try:
            runner = MissionRunner(gateway, store, step_timeout_s=120)
            mission_id = runner.start(STEPS, "through the ros2 executable")
            assert runner.wait(240)
            check_in_order(store, mission_id, gateway)
        finally:
            gateway.close()
            store.close()
