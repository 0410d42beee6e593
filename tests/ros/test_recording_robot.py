"""`astiop record` on a robot over ROS 2 (the emulated robot's processes): every topic logged
on its receive clock (tests/system/test_recording.py: recordings of the simulator)."""

import pytest

from tests.cli_runner import run_cli


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
