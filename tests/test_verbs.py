"""A verb is one module (astiop/ros2/verbs/): the registry, and `ros2 topic bw` on every
transport: the simulator in process, the emulated `ros2` (CLI transport) and rclpy on DDS."""

from __future__ import annotations

import importlib

import pytest

from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.grammar import SUPPORTED, CommandSyntaxError, parse
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.transport import Transport
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend

PRIMITIVES = [name for name in vars(Transport) if not name.startswith("_")]


def test_each_verb_is_the_module_named_for_it_and_the_grammar_accepts_exactly_those():
    assert set(VERBS) == SUPPORTED and ("topic", "bw") in VERBS
    for (noun, sub), verb in VERBS.items():
        module = importlib.import_module(f"astiop.ros2.verbs.{noun}_{sub}")
        assert module.VERB is verb and verb.name == f"{noun} {sub}"
        assert (verb.enough is None) == (verb.means != "sample"), verb.name


def test_the_simulator_gives_every_verb_what_it_runs_on():
    from astiop.transports.simulator.verbs import SimVerbs  # SimBackend.verbs

    missing = [name for name in PRIMITIVES if not callable(getattr(SimVerbs, name, None))]
    assert not missing, missing


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

    unserved = [v.name for k, v in VERBS.items() if k not in DdsRos2.VERBS and v.means != "query"]
    assert not unserved, unserved


def test_bw_parses_as_ros2cli_declares_it_on_both_distros():
    for distro in ("humble", "jazzy"):
        cmd = parse("ros2 topic bw /scan -w 5", distro)
        assert cmd.key == ("topic", "bw") and cmd.name == "/scan" and cmd.options["window"] == 5
        assert parse("ros2 topic bw scan", distro).options["window"] == 100  # bw.py's default
        with pytest.raises(CommandSyntaxError, match="--window"):
            parse("ros2 topic bw /scan --window 0", distro)
        with pytest.raises(CommandSyntaxError, match="unrecognized arguments: --once"):
            parse("ros2 topic bw /scan --once", distro)


def sim_gateway() -> RobotGateway:
    return RobotGateway(SimBackend(Simulator(seed=0), None), SafetyPolicy())


def test_bw_on_the_simulator_reports_twice_a_second_apart_what_the_scan_weighs():
    from astiop.ros2.cdr import serialized_size

    gateway = sim_gateway()
    try:
        scan = gateway.run("ros2 topic echo /scan --once").values
        size = serialized_size("sensor_msgs/msg/LaserScan", scan)
        assert 360 * 4 < size < 360 * 4 + 200  # the ranges, float32, and the header
        r = gateway.run("ros2 topic bw /scan")
        assert r.executed and not r.error and r.provenance == "measured", r.error
        lines = r.output.splitlines()
        assert lines[0] == "Subscribed to [/scan]" and len(lines) == 5, r.output
        # 10 Hz: 11 messages in the first second (the first and the one at 1.0 s), 21 in two
        assert lines[1] == f"{11 * size / 1000:.2f} KB/s from 11 messages", r.output
        kb = f"{size / 1000:.2f} KB"
        assert lines[2] == f"\tMessage size mean: {kb} min: {kb} max: {kb}", r.output
        assert r.values["messages"] == 21 and r.values["reports"] == 2
        assert r.values["bytes_per_s"] == pytest.approx(21 * size / 2.0, rel=0.01)
        w = gateway.run("ros2 topic bw /scan -w 4")
        assert "from 4 messages" in w.output and w.values["messages"] == 4, w.output
        idle = gateway.run("ros2 topic bw /plan")  # no goal: nothing is published on it
        assert idle.error and "not being published" in idle.error
    finally:
        gateway.close()


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


def test_find_lists_the_topics_of_a_type_as_ros2cli_prints_them():
    """A verb added as one module and this test: the grammar, validation and every transport
    take it from the registry (the simulator here; the emulated ros2 runs it the same way)."""
    gateway = sim_gateway()
    try:
        r = gateway.run("ros2 topic find sensor_msgs/msg/LaserScan")
        assert r.executed and not r.error and r.output == "/scan\n", (r.error, r.output)
        tf = gateway.run("ros2 topic find tf2_msgs/msg/TFMessage -c")
        assert tf.output == "2\n" and tf.values == ["/tf", "/tf_static"], tf.output
        assert gateway.run("ros2 topic find no_pkg/msg/None").output == ""
    finally:
        gateway.close()


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


def test_the_line_sent_names_the_topic_where_it_was_typed_after_an_options_value():
    from astiop.ros2.catalog import astibot_catalog
    from astiop.ros2.render import sent_argv
    from astiop.ros2.validation import validate

    checked = validate("ros2 topic hz -w 5 scan", astibot_catalog())
    assert sent_argv(checked) == ["topic", "hz", "-w", "5", "/scan"]
    checked = validate("ros2 topic bw --window 3 odom", astibot_catalog())
    assert sent_argv(checked) == ["topic", "bw", "--window", "3", "/odom"]


def test_hz_and_echo_on_the_simulator_run_the_verbs_one_implementation():
    gateway = sim_gateway()
    try:
        hz = gateway.run("ros2 topic hz /odom")  # published at 50 Hz on the simulator's clock
        assert hz.values == {"average_rate": 50.0, "windows": 2}, hz.output
        assert hz.output.startswith("average rate: 50.000\n\tmin: 0.020s max: 0.020s")
        field = gateway.run("ros2 topic echo /robot_pose --once --field x")
        assert field.output == "1.15\n---\n" and field.values == 1.15, field.output
        bad = gateway.run("ros2 topic echo /robot_pose --once --field nope")
        assert bad.error == "/robot_pose has no field nope", bad.error
    finally:
        gateway.close()
