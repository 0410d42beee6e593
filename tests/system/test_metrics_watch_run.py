"""`astiop watch run --metrics` on the simulator: a scrape reads the simulated robot's battery."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import httpx
import pytest

from tests.unit.test_metrics import _samples


@pytest.mark.slow
def test_watch_run_serves_the_simulated_robots_battery(tmp_path):
    env = {
        **os.environ,
        "ASTIOP_SIM__BATTERY": "0.5",
        "ASTIOP_SIM__SPEED": "1",
        "ASTIOP_ROBOT__BACKEND": "sim",
    }
    argv = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "w.db"), "watch", "run"]
    proc = subprocess.Popen(
        [*argv, "--metrics", "127.0.0.1:0"], env=env, stderr=subprocess.PIPE, text=True
    )
    try:
        url = ""
        deadline = time.monotonic() + 60
        while not url and time.monotonic() < deadline:
            line = proc.stderr.readline()
            assert line, "watch run ended before it served its metrics"
            if line.startswith("metrics at "):
                url = line.split()[-1]
        got: dict = {}
        robot = (("robot", "astibot"),)
        while ("astiop_robot_battery_ratio", robot) not in got and time.monotonic() < deadline:
            got = _samples(httpx.get(url, timeout=10).text)
            time.sleep(0.2)
        assert 0.49 < got[("astiop_robot_battery_ratio", robot)] < 0.56  # docked: charging
        assert got[("astiop_robot_estop", robot)] == 0
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=30)
    assert proc.returncode == 0
