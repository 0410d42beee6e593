"""The E-STOP wins over anything in flight: in this process (a race), and from another process
(`astiop estop` while `astiop exec` runs a timed publish), on each transport."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import pytest

from astiop.transports.errors import BackendError
from astiop.transports.inflight import InFlight
from tests.emulator import cmd_vel_received, emulated_robot, on_path
from tests.ros import until

PUBLISH = (
    "ros2 topic pub -t 300 -r 10 /cmd_vel geometry_msgs/msg/Twist "
    "'{linear: {x: 0.3}}'"
)  # 30 s of motion unless something ends it
IN_FLIGHT_S = 0.5  # a message sent as its publisher was ended, still on its way (a loaded
# machine); a publish that goes on sends five in that time


def _actuate(inflight: InFlight, i: int, go, stopped, sent_after: list[str]) -> None:
    go.wait()
    try:
        job = inflight.start(f"publish {i}")
    except BackendError:
        return  # refused: the E-STOP came first
    for _ in range(50):
        try:
            with job.sending():
                if stopped.is_set():
                    sent_after.append(job.what)
        except BackendError:
            return  # ended by the E-STOP
    job.done()


def test_a_job_raced_by_the_estop_is_refused_or_ended_and_sends_nothing_after():
    """Jobs start and send while the E-STOP comes: once stop_all() returns, none sends again,
    and none starts."""
    for _ in range(200):
        inflight = InFlight()
        sent_after: list[str] = []
        stopped = threading.Event()
        go = threading.Barrier(5)
        threads = [
            threading.Thread(target=_actuate, args=(inflight, i, go, stopped, sent_after))
            for i in range(4)
        ]
        for t in threads:
            t.start()
        go.wait()
        inflight.stop_all()
        stopped.set()
        for t in threads:
            t.join(5)
            assert not t.is_alive(), "a job was left waiting"
        assert not sent_after, sent_after
        with pytest.raises(BackendError, match="E-STOP is engaged"):
            inflight.start("after")
        assert not inflight.busy


def test_an_ended_job_runs_its_stop_action_even_when_it_is_given_late():
    inflight = InFlight()
    job = inflight.start("goal")
    inflight.stop_all()
    ran: list[int] = []
    with pytest.raises(BackendError, match="E-STOP ended it"):
        job.on_estop(lambda: ran.append(1))  # its process was spawned as the E-STOP came
    assert ran == [1]


def _cli(db, *args: str) -> list[str]:
    return [sys.executable, "-m", "astiop", "--db", str(db), "--robot", "ros2", *args]


def moving(twists: list[dict]) -> list[dict]:
    return [t for t in twists if t["twist"]["linear"]["x"] != 0.0]


@pytest.mark.slow
def test_estop_from_another_process_ends_a_timed_publish_on_the_cli_transport(
    monkeypatch, tmp_path
):
    """`astiop exec` runs `topic pub -t 300 -r 10`; `astiop estop` from a second shell kills its
    publisher: nothing moving reaches the robot once the E-STOP's zero Twists start."""
    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        db = tmp_path / "shared.db"
        publisher = subprocess.Popen(
            _cli(db, "exec", "--yes", PUBLISH),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            assert until(lambda: len(moving(cmd_vel_received(folder))) >= 3, 30), (
                "the timed publish never reached the robot"
            )
            out = subprocess.run(_cli(db, "estop"), capture_output=True, text=True, timeout=60)
            assert out.returncode == 0, out.stderr
            _, err = publisher.communicate(timeout=25)  # not the 30 s it asked for
        finally:
            if publisher.poll() is None:
                publisher.kill()
        assert publisher.returncode == 1 and "E-STOP ended it" in err, err
        twists = cmd_vel_received(folder)
        first_zero = next(i for i, t in enumerate(twists) if t["twist"]["linear"]["x"] == 0.0)
        assert not moving(twists[first_zero:]), twists[first_zero:]
        time.sleep(1.0)
        assert not moving(cmd_vel_received(folder)[len(twists) :])


@pytest.mark.slow
def test_a_publish_and_the_estop_raced_in_one_process_leave_the_robot_stopped(
    monkeypatch, tmp_path
):
    """On the CLI transport, the E-STOP while the publish's ros2 process is starting (the
    gateway's own, in this process): the publish is refused or ended, and no moving
    Twist follows the E-STOP's zeros."""
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy
    from astiop.transports.ros2cli.backend import Ros2Backend

    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        gateway = RobotGateway(Ros2Backend("ros2", 10.0, stream=False), SafetyPolicy())
        gateway.start()
        try:
            go = threading.Barrier(2)
            results = []

            def publish() -> None:
                go.wait()
                results.append(gateway.run(PUBLISH.replace("-t 300", "-t 30"), lambda _c: True))

            thread = threading.Thread(target=publish)
            thread.start()
            go.wait()
            time.sleep(0.5)  # the publisher is starting: a ros2 process under way
            gateway.estop()
            thread.join(20)
            assert not thread.is_alive(), "the publish outlived the E-STOP"
            result = results[0]
            assert result.error or not result.executed, result
            assert until(lambda: len(cmd_vel_received(folder)) >= 10, 15)  # the zero burst
            time.sleep(1.0)
            twists = cmd_vel_received(folder)
            first_zero = next(i for i, t in enumerate(twists) if t["twist"]["linear"]["x"] == 0)
            assert not moving(twists[first_zero:]), twists
        finally:
            gateway.close()


@pytest.mark.slow
@pytest.mark.ros
def test_estop_from_another_process_ends_a_timed_publish_on_rclpy(tmp_path):
    """The same on real DDS against `astiop sim node`, the robot's own /odom read by a node of
    the test's: the speed comes to zero and stays there, and the publish ends early."""
    from tests.ros import require_ros, ros_client, sim_node

    require_ros()
    from nav_msgs.msg import Odometry

    env = {**os.environ, "ASTIOP_ROBOT__ROS2_TRANSPORT": "rclpy"}
    db = tmp_path / "shared.db"
    with sim_node(speed=1.0), ros_client() as client:
        odom = client.collect(Odometry, "/odom")
        undock = _cli(db, "exec", "--yes", "ros2 service call /undock std_srvs/srv/Trigger")
        subprocess.run(undock, capture_output=True, text=True, timeout=60, env=env, check=True)

        def speed() -> float:
            return abs(odom[-1][1].twist.twist.linear.x) if odom else 0.0

        assert until(lambda: speed() > 0.05, 15) and until(lambda: speed() < 0.01, 30)  # undocked
        publisher = subprocess.Popen(
            _cli(db, "exec", "--yes", PUBLISH.replace("x: 0.3", "x: -0.3")),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        try:
            assert until(lambda: speed() > 0.1, 30), "the timed publish never moved the robot"
            out = subprocess.run(
                _cli(db, "estop"), capture_output=True, text=True, timeout=60, env=env
            )
            assert out.returncode == 0, out.stderr
            _, err = publisher.communicate(timeout=25)
        finally:
            if publisher.poll() is None:
                publisher.kill()
        assert publisher.returncode == 1 and "E-STOP ended it" in err, err
        assert until(lambda: speed() < 0.01, 5), speed()
        stopped_at = time.monotonic()
        time.sleep(1.5)
        assert all(abs(m.twist.twist.linear.x) < 0.01 for t, m in odom if t > stopped_at), (
            "the robot moved again after the E-STOP"
        )


@pytest.mark.slow
def test_a_command_is_journaled_before_the_robot_is_told(monkeypatch, tmp_path):
    """`astiop exec` killed (-9) in the middle of a timed publish leaves its record: sent, and
    that it did not finish."""
    import sqlite3

    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        db = tmp_path / "journal.db"
        publisher = subprocess.Popen(
            _cli(db, "exec", "--yes", PUBLISH),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        try:
            assert until(lambda: len(moving(cmd_vel_received(folder))) >= 3, 30)
        finally:
            publisher.kill()
            publisher.wait(10)
    with sqlite3.connect(db) as conn:
        rows = conn.execute("SELECT command, executed, reason, source FROM commands").fetchall()
    assert rows == [(PUBLISH, 1, "sent to the robot; astiop ended before it finished", "exec")], (
        rows
    )


@pytest.mark.slow
async def test_estop_from_another_process_ends_an_mcp_move_on_the_cli_transport(
    monkeypatch, tmp_path
):
    """An outside agent's `move` (3 s, the most it may ask) through `astiop mcp`, and `astiop
    estop` from a second shell: the tool says the E-STOP stopped it early, and nothing moving
    follows the E-STOP's zeros."""
    import asyncio

    from mcp import Client, StdioServerParameters

    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        db = tmp_path / "mcp.db"
        args = _cli(db, "mcp", "--approve-actuation")[1:]
        server = StdioServerParameters(command=sys.executable, args=args, env=dict(os.environ))
        async with Client(server) as client:
            move = asyncio.create_task(client.call_tool("move", {"vx": 0.3, "seconds": 3}))
            loop = asyncio.get_running_loop()
            moved = await loop.run_in_executor(
                None, until, lambda: len(moving(cmd_vel_received(folder))) >= 3, 60
            )
            assert moved, "the move never reached the robot"
            out = await asyncio.to_thread(
                subprocess.run, _cli(db, "estop"), capture_output=True, text=True, timeout=60
            )
            assert out.returncode == 0, out.stderr
            result = await asyncio.wait_for(move, 30)
        text = "\n".join(c.text for c in result.content)
        assert result.is_error and "stopped early" in text and "E-STOP" in text, text
        await asyncio.sleep(1.0)
        twists = cmd_vel_received(folder)
        first_zero = next(
            i
            for i, t in enumerate(twists)
            if t["twist"]["linear"]["x"] == 0.0 and i > 0 and twists[i - 1]["twist"]["linear"]["x"]
        )
        # a message the move's publisher had already sent when it was ended may still land
        # just after a zero from another writer (DDS orders no two writers); none later
        zeroed = twists[first_zero]["mono"]
        late = [t for t in moving(twists[first_zero:]) if t["mono"] > zeroed + IN_FLIGHT_S]
        assert not late and not moving(twists[-1:]), twists[first_zero:]


@pytest.mark.slow
def test_astiop_estop_release_lets_go_of_a_robot_held_by_a_bare_stop(monkeypatch, tmp_path):
    """A robot the agent stopped (/stop: it latches its own stop, the store holds nothing) is
    released by `astiop estop --release`, which calls its /release."""
    from tests.emulator import ros2_calls

    with emulated_robot(speed=4.0) as folder:
        on_path(monkeypatch, folder)
        db = tmp_path / "held.db"
        stop = _cli(db, "exec", "--yes", "ros2 service call /stop std_srvs/srv/Trigger")
        subprocess.run(stop, capture_output=True, text=True, timeout=60, check=True)
        out = subprocess.run(
            _cli(db, "estop", "--release", "--yes"), capture_output=True, text=True, timeout=90
        )
        assert out.returncode == 0, out.stderr
        assert "the robot's own stop released (/release)" in out.stdout, out.stdout
        assert ["service", "call", "/release"] in [c[:3] for c in ros2_calls(folder)]
