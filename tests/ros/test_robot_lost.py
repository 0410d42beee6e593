"""The robot dies mid-goal (`kill -9`): astiop says it lost contact within seconds, never that the
goal succeeded or aborted, stores the turn's outcome as lost, hangs nowhere, and reconnects by
itself when the robot comes back; on both transports."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
import time

import pytest

from tests.emulator import emulated_robot, on_path
from tests.ros import until

pytestmark = pytest.mark.slow
GOTO = 'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"'
YES = lambda _c: True  # noqa: E731


def said(gateway, words: str) -> bool:
    return any(words in e.message for e in gateway.events_since(0))


def test_chat_says_it_lost_the_robot_killed_mid_goal_and_stores_it(monkeypatch, tmp_path):
    robots: list = []
    with emulated_robot(processes=robots) as folder:
        on_path(monkeypatch, folder)
        db = tmp_path / "lost.db"
        chat = subprocess.Popen(
            [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2", "chat",
             "--model", "rules", "--yes", "send the robot to shipping"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            log = folder / "ros2.log"
            assert until(lambda: log.exists() and "goto_position" in log.read_text(), 60)
            time.sleep(3.0)  # the goal is under way
            robots[0].kill()
            killed = time.monotonic()
            out, err = chat.communicate(timeout=30)  # nothing hangs
            took = time.monotonic() - killed
        finally:
            if chat.poll() is None:
                chat.kill()
    assert "lost contact with the robot during the goal to shipping" in out, out + err
    assert "succeeded" not in out and "aborted" not in out, out
    assert took < 20, took  # within a few seconds; not the 90 s wait for an arrival
    with sqlite3.connect(db) as conn:
        assert conn.execute("SELECT outcome FROM interactions").fetchall() == [("lost",)]


def test_the_cli_transport_loses_the_robot_and_reconnects_when_it_comes_back(monkeypatch):
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.transports.ros2cli.backend import Ros2Backend

    robots: list = []
    with emulated_robot(speed=4.0, processes=robots) as folder:
        on_path(monkeypatch, folder)
        gateway = RobotGateway(Ros2Backend("ros2", 10.0), SafetyPolicy())
        gateway.start()
        try:
            assert until(lambda: gateway.state().pose is not None, 30)
            assert gateway.run(GOTO, confirm=YES).values["success"]
            assert until(lambda: gateway.state().state_word == "navigating", 15)
            robots[0].kill()
            t0 = time.monotonic()
            assert gateway.wait_until_idle(30) == "lost"
            assert time.monotonic() - t0 < 10
            assert gateway.state().state_word == "lost" and said(gateway, "lost contact")
            with emulated_robot(speed=4.0, folder=folder):
                assert until(lambda: gateway.state().state_word not in ("lost",), 40)
                assert said(gateway, "reconnected"), gateway.events_since(0)
        finally:
            gateway.close()


@pytest.mark.ros
def test_rclpy_loses_the_sim_node_killed_mid_goal_and_reconnects(tmp_path):
    from tests.ros import require_ros, sim_node

    require_ros()
    from astiop.config import load_settings
    from astiop.robot.factory import make_robot_gateway

    settings = load_settings(
        {"llm": {"model": "rules"}, "robot": {"backend": "ros2", "ros2_transport": "rclpy"}},
        env={},
        path=tmp_path / "none.toml",
    )
    with sim_node(speed=4.0) as node:
        gateway = make_robot_gateway(settings, None)
        gateway.start()
        try:
            assert until(lambda: gateway.state().status is not None, 30)
            gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=YES)
            assert until(lambda: (gateway.state().status.speed or 0) > 0.05, 15)
            node.kill()
            t0 = time.monotonic()
            assert gateway.wait_until_idle(30) == "lost"
            assert time.monotonic() - t0 < 10
            assert gateway.state().state_word == "lost" and said(gateway, "lost contact")
            with sim_node(speed=4.0):
                back = gateway.state
                assert until(lambda: back().state_word != "lost" and back().pose is not None, 40)
                assert said(gateway, "reconnected"), gateway.events_since(0)
        finally:
            gateway.close()
    assert os.environ.get("ROS_LOCALHOST_ONLY") == "1"
