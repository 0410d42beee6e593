"""Sessions as MCAP, read back with mcap-ros2-support's own reader (not astiop's code)."""

import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from astiop.recording import summary
from astiop.ros2.catalog import astibot_catalog
from tests.cli_runner import run_cli

ROS_TOPICS = astibot_catalog().recorded_topics()


def decoded(path, topics=ROS_TOPICS):
    """(topic, message) as mcap-ros2-support's decoder reads them."""
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _schema, channel, _message, msg in reader.iter_decoded_messages(topics=list(topics)):
            yield channel.topic, msg


def test_a_recorded_trip_decodes_with_the_ros2_reader(tmp_path, monkeypatch):
    monkeypatch.setenv("ASTIOP_SIM__SPEED", "10")
    path = tmp_path / "trip.mcap"
    out = run_cli(
        "--db",
        str(tmp_path / "r.db"),
        "record",
        "--goto",
        "inspection_zone_a",
        "--scan-hz",
        "5",
        "--json",
        str(path),
    )
    assert out.returncode == 0, out.stderr
    counts = json.loads(out.stdout)["messages"]
    for topic in (
        "/robot_pose",
        "/odom",
        "/battery_status",
        "/robot_status",
        "/scan",
        "/obstacles",
        "/plan",
        "/tf",
        "/diagnostics",
        "/conveyor/status",
    ):
        assert counts.get(topic, 0) > 0, topic
    assert summary(path) == counts  # the file's own summary lists each topic's count
    poses, scans, batteries = [], [], []
    for topic, msg in decoded(path):
        if topic == "/robot_pose":
            poses.append((msg.x, msg.y))
        elif topic == "/scan":
            scans.append(len(msg.ranges))
        elif topic == "/battery_status":
            batteries.append(msg.percentage)
            assert msg.power_supply_technology == 8  # VRLA, on Jazzy
    assert math.dist(poses[-1], (15.0, 3.5)) < 0.3 and math.dist(poses[0], (15.0, 3.5)) > 5
    assert set(scans) == {360}
    assert all(0.0 < b <= 1.0 for b in batteries)
    with path.open("rb") as fh:  # the JSON channels carry their JSON schema
        reader = make_reader(fh)
        info = reader.get_summary()
        events = [c for c in info.channels.values() if c.topic == "/astiop/events"]
        assert events and events[0].message_encoding == "json"
        assert info.schemas[events[0].schema_id].encoding == "jsonschema"


@pytest.mark.slow
def test_a_recording_killed_mid_way_keeps_its_chunks_and_repairs(tmp_path):
    path = tmp_path / "cut.mcap"
    env = {**os.environ, "ASTIOP_SIM__SPEED": "5"}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "astiop",
            "--db",
            str(tmp_path / "k.db"),
            "record",
            "--duration",
            "60",
            str(path),
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (not path.exists() or path.stat().st_size < 20_000):
        time.sleep(0.2)  # a flush every 2 s: wait for a few chunks
    time.sleep(2.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait(10)
    out = run_cli("record", "--repair", "--json", str(path))
    assert out.returncode == 0, out.stderr
    recovered = json.loads(out.stdout)["messages"]
    assert recovered.get("/robot_pose", 0) > 10 and recovered.get("/battery_status", 0) > 0
    fixed = tmp_path / "cut.repaired.mcap"
    assert summary(fixed) == recovered
    assert sum(1 for _ in decoded(fixed, ["/scan"])) > 0


def test_record_refuses_bad_input_in_one_line(tmp_path):
    db = str(tmp_path / "b.db")
    for args in (
        ("record", "--goto", "nowhere"),
        ("record", "--duration", "nan"),
        ("record", "--repair", str(tmp_path / "none.mcap")),
    ):
        out = run_cli("--db", db, *args)
        assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1, out.stderr


@pytest.mark.slow
def test_a_recording_on_the_robot_logs_every_topic_on_its_receive_clock(tmp_path, monkeypatch):
    from astiop.recording.reader import Recording
    from tests.emulator import emulated_robot, on_path

    with emulated_robot(speed=4.0) as robot:  # its stamps run 4x faster than the wall clock
        on_path(monkeypatch, robot)
        path = tmp_path / "robot.mcap"
        out = run_cli("--db", str(tmp_path / "r.db"), "--robot", "ros2", "record",
                      "--duration", "3", "--json", str(path))  # fmt: skip
    assert out.returncode == 0, out.stderr
    rec = Recording(path)
    assert rec.backend == "ros2" and 1.5 < rec.duration_s < 4.0  # wall seconds, not 12
    t0 = float(rec.metadata["robot_t0"])
    for topic in ("/robot_pose", "/battery_status", "/robot_status", "/scan"):
        times = rec.channels[topic].times
        assert times and all(t0 - 1 <= t / 1e9 <= t0 + 5 for t in times), topic
