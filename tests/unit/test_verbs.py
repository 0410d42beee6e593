"""A verb is one module (astiop/ros2/verbs/): the registry, and the verbs on the simulator in
process (tests/ros/test_verbs_transports.py: the emulated `ros2` and rclpy on DDS)."""

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
        assert (verb.output_complete is None) == (verb.runs_as != "sample"), verb.name


def test_the_simulator_gives_every_verb_what_it_runs_on():
    from astiop.transports.simulator.verbs import SimVerbs  # SimBackend.verbs

    missing = [name for name in PRIMITIVES if not callable(getattr(SimVerbs, name, None))]
    assert not missing, missing


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


def test_the_command_to_approve_reads_plainly_and_means_in_a_shell_what_is_sent():
    """A Nav2 goal's empty behavior_tree was shown as `'"'"''"'"'` in the approval dialog."""
    import shlex

    from astiop.ros2.catalog import astibot_catalog
    from astiop.ros2.render import sent_argv, sent_text
    from astiop.ros2.validation import validate

    goal = (
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        "'{pose: {header: {frame_id: map}, pose: {position: {x: 28.0, y: 4.0}}}}'"
    )
    checked = validate(goal, astibot_catalog())
    shown = sent_text(checked)
    assert "behavior_tree: ''}" in shown and "'\"'\"'" not in shown
    assert shlex.split(shown)[1:] == sent_argv(checked)  # the words a shell makes of it
