"""`astiop sim node --robots N` over real DDS: N ASTIbots in one warehouse, each under its own
namespace (or, with --domains, each on a domain of its own), found with --fleet auto, one of
them sent by name while the others stay on their docks, and all stopped at once."""

from __future__ import annotations

import contextlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.ros import SimNode, quiet_domain, require_ros, ros_client, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]
SHIPPING = (37.6, 4.0)


@contextlib.contextmanager
def fleet_node(*args: str, env: dict | None = None):
    quiet_domain()
    node = SimNode(speed=4.0, robot_args=args, env=env)
    try:
        node.wait_ready()
        yield node
    finally:
        node.stop()


def astiop(db: Path, *args: str, env=None, timeout: float = 120) -> subprocess.CompletedProcess:
    cli = [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2"]
    cli += ["--ros2-transport", "rclpy"]
    return subprocess.run([*cli, *args], capture_output=True, text=True, timeout=timeout, env=env)


def test_two_astibots_in_one_warehouse_each_reached_by_its_name(tmp_path, monkeypatch):
    require_ros()
    from geometry_msgs.msg import Pose2D

    # a domain of its own: a fleet node's many nodes must never be left in the worker's
    # discovery data for the next test's robot (its /astibot_1/navigator is a "navigator")
    monkeypatch.setenv("ROS_DOMAIN_ID", str((int(os.environ["ROS_DOMAIN_ID"]) + 25) % 102))

    db = tmp_path / "fleet.db"
    # two robots: a fleet node costs ~14 % of a core per robot, and the suite runs beside it
    with fleet_node("--robots", "2") as node, ros_client("watcher") as client:
        assert "2 ASTIbots up as ROS 2 nodes under /astibot_1 … /astibot_2" in "\n".join(node.lines)
        poses = {i: client.collect(Pose2D, f"/astibot_{i}/robot_pose") for i in (1, 2)}
        out = astiop(db, "--fleet", "auto", "fleet", "list", "--json")
        assert out.returncode == 0, out.stderr[-2000:]
        rows = {r["name"]: r for r in json.loads(out.stdout)}
        assert set(rows) == {"astibot_1", "astibot_2"}, rows
        for i in (1, 2):  # each on its own dock, 1 m apart along the west wall
            row = rows[f"astibot_{i}"]
            assert row["make"] == "astibot" and row["state"] == "charging", row
            assert abs(row["x_m"] - 1.15) < 0.05 and abs(row["y_m"] - (2.0 + i)) < 0.05, row

        out = astiop(db, "--fleet", "auto", "--robot-name", "astibot_2", "chat", "-m", "rules",
                     "--yes", "go to shipping", timeout=180)  # fmt: skip
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        assert "arrived: shipping" in out.stdout, out.stdout + out.stderr[-3000:]
        assert until(lambda: poses[2] and math.dist(_xy(poses[2]), SHIPPING) < 0.3, 10)
        assert math.dist(_xy(poses[1]), (1.15, 3.0)) < 0.02, _xy(poses[1])  # never left its dock

        out = astiop(db, "--fleet", "auto", "estop", "--all")
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        for i in (1, 2):
            assert f"astibot_{i}: E-STOP engaged" in out.stdout, out.stdout
        out = astiop(db, "--fleet", "auto", "--robot-name", "astibot_2", "chat", "-m", "rules",
                     "--yes", "go to the assembly station")  # fmt: skip
        assert "E-STOP" in out.stdout + out.stderr, out.stdout
        out = astiop(db, "--fleet", "auto", "estop", "--release", "--all", "--yes")
        assert out.returncode == 0, out.stdout + out.stderr[-2000:]
        out = astiop(db, "--fleet", "auto", "fleet", "list", "--json")
        states = {r["name"]: r["state"] for r in json.loads(out.stdout)}
        assert states == {"astibot_1": "charging", "astibot_2": "idle"}, states  # let go


def test_with_domains_each_robot_is_un_namespaced_on_a_domain_of_its_own(tmp_path):
    require_ros()
    base = 100  # above every pytest worker's domain (tests/conftest.py); 101 is the last valid
    env = {**os.environ, "ROS_DOMAIN_ID": str(base)}
    with fleet_node("--robots", "2", "--domains", env=env) as node:
        said = "\n".join(node.lines)
        assert f"astibot_1 on ROS_DOMAIN_ID={base}, astibot_2 on ROS_DOMAIN_ID={base + 1}" in said
        for i in (1, 2):
            on = {**os.environ, "ROS_DOMAIN_ID": str(base + i - 1)}
            out = astiop(tmp_path / "d.db", "exec", "ros2 topic echo /robot_pose --once", env=on)
            assert out.returncode == 0, out.stdout + out.stderr[-2000:]
            assert "x: 1.15" in out.stdout and f"y: {2.0 + i}" in out.stdout, out.stdout


def _xy(got: list) -> tuple[float, float]:
    msg = got[-1][1]
    return (msg.x, msg.y)
