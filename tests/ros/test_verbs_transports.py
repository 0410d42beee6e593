"""The verbs on the transports that start processes: rclpy on real ROS 2 and the emulated ros2
(tests/unit/test_verbs.py holds the verbs on the simulator, in process)."""

from __future__ import annotations

import pytest

from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.transport import Transport
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend

PRIMITIVES = [name for name in vars(Transport) if not name.startswith("_")]


@pytest.mark.ros
def test_rclpy_gives_every_verb_what_it_runs_on():
    from tests.ros import require_ros

    require_ros()
    from astiop.transports.rclpy.verbs import RclpyVerbs  # what RclpyBackend runs verbs on

    missing = [name for name in PRIMITIVES if not callable(getattr(RclpyVerbs, name, None))]
    assert not missing, missing


@pytest.mark.ros
def test_the_emulated_ros2_over_dds_runs_every_verb():
    """Its own emulation, or (a verb that only reads the graph) the verb's module."""
    from tests.ros import require_ros

    require_ros()
    from astiop.robot_programs.emulated_cli.dds import DdsRos2

    unserved = [v.name for k, v in VERBS.items() if k not in DdsRos2.VERBS and v.runs_as != "query"]
    assert not unserved, unserved


def test_bw_on_the_cli_transport_reads_what_the_emulated_ros2_prints(monkeypatch):
    from astiop.transports.ros2cli.backend import Ros2Backend
    from tests.emulator import emulated_robot, on_path, ros2_calls

    with emulated_robot() as folder:  # real time: arrivals on the wall clock
        on_path(monkeypatch, folder)
        gateway = RobotGateway(Ros2Backend("ros2", 10.0, stream=False), SafetyPolicy())
        gateway.start()
        try:
            r = gateway.run("ros2 topic bw /battery_status", timeout=15)
            assert r.executed and not r.error, r.error
            assert r.output.startswith("Subscribed to [/battery_status]\n"), r.output
            assert r.values["reports"] >= 2 and r.values["bytes_per_s"] > 0, r.values
            assert ["topic", "bw", "/battery_status"] in ros2_calls(folder)  # as typed
        finally:
            gateway.close()


@pytest.mark.ros
@pytest.mark.slow
def test_bw_through_rclpy_counts_the_bytes_dds_carries(tmp_path):
    """rclpy takes the scans raw: their sizes are what DDS carried, and what the simulator in
    process computes for the same message."""
    from astiop.config import load_settings
    from astiop.robot.factory import make_robot_gateway
    from astiop.ros2.cdr import serialized_size
    from astiop.store import Store
    from tests.ros import require_ros, sim_node, whole_robot

    require_ros()
    settings = load_settings(
        {"llm": {"model": "rules"}, "robot": {"backend": "ros2", "ros2_transport": "rclpy"}},
        env={},
        path=tmp_path / "none.toml",
    )
    with sim_node():
        store = Store(tmp_path / "bw.db")
        gateway = make_robot_gateway(settings, store)
        gateway.start()
        try:
            whole_robot(gateway)
            scan = gateway.run("ros2 topic echo /scan --once").values
            r = gateway.run("ros2 topic bw /scan", timeout=15)
            assert r.executed and not r.error, r.error
            size = serialized_size("sensor_msgs/msg/LaserScan", scan)
            assert f"Message size mean: {size / 1000:.2f} KB" in r.output, (size, r.output)
            assert 8 * size < r.values["bytes_per_s"] < 13 * size, r.values  # 10 Hz
        finally:
            gateway.close()
            store.close()


@pytest.mark.ros
def test_the_computed_size_is_the_size_rclpy_serializes():
    from tests.ros import require_ros

    require_ros()
    from rclpy.serialization import serialize_message

    from astiop.ros2.cdr import serialized_size
    from astiop.ros2.message_objects import interface_class, to_message

    backend = SimBackend(Simulator(seed=0), None)
    for name, spec in backend.catalog.topics.items():
        message = backend.message(name)
        if not message:
            continue
        wire = serialize_message(to_message(interface_class(spec.type), message))
        assert serialized_size(spec.type, message) == len(wire), name
    trigger = interface_class("std_srvs/srv/Trigger")  # an empty request; short replies
    assert serialized_size("std_srvs/srv/Trigger", {}) == len(serialize_message(trigger.Request()))
    for text in ("", "a", "abc"):
        reply = {"success": True, "message": text}
        wire = serialize_message(to_message(trigger.Response, reply))
        assert serialized_size("std_srvs/srv/Trigger", reply, part=1) == len(wire), text


def test_find_on_the_cli_transport_runs_the_same_verb_in_the_emulated_ros2(monkeypatch):
    from astiop.transports.ros2cli.backend import Ros2Backend
    from tests.emulator import emulated_robot, on_path, ros2_calls

    with emulated_robot() as folder:
        on_path(monkeypatch, folder)
        gateway = RobotGateway(Ros2Backend("ros2", 10.0, stream=False), SafetyPolicy())
        gateway.start()
        try:
            r = gateway.run("ros2 topic find nav_msgs/msg/Odometry")
            assert r.executed and not r.error and r.output == "/odom\n", (r.error, r.output)
            assert ["topic", "find", "nav_msgs/msg/Odometry"] in ros2_calls(folder)
        finally:
            gateway.close()
