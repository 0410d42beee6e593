"""One E-STOP across stations: separate astiop processes, each with its own database and settings
(as separate machines have), on one ROS domain, against a robot with no stop latch of its own (a
TurtleBot3 under Nav2) and one with its own (the ASTIbot). A press anywhere holds every station,
a station started later too; its release is a person's and holds everywhere; a database that
cannot be written never keeps the stop from the robot; no outside agent releases a robot."""

from __future__ import annotations

import contextlib
import os
import re
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from astiop.robot.safety import releases_a_stop
from astiop.ros2.catalog import Catalog, ServiceSpec
from astiop.ros2.validation import validate
from astiop.store import Store
from tests.ros import until

TRIGGER = "std_srvs/srv/Trigger"
STAMPED_PUB = (
    "ros2 topic pub -t 290 -r 10 /cmd_vel geometry_msgs/msg/TwistStamped "
    "'{twist: {linear: {x: 0.05}}}'"
)
GOAL = (
    "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
    "'{pose: {header: {frame_id: map}, pose: {position: {x: 1.0, y: 0.5}, "
    "orientation: {w: 1.0}}}}'"
)


def test_an_outside_agent_releases_no_robot_under_any_namespace_or_spelling():
    catalog = Catalog(
        services={
            name: ServiceSpec(name, TRIGGER, "/base", True)
            for name in ("/release", "/astibot_2/release", "/stop", "/brake/let_go")
        },
    )

    def call(name: str):
        return validate(f"ros2 service call {name} {TRIGGER}", catalog)

    assert releases_a_stop(call("/release")) and releases_a_stop(call("/astibot_2/release"))
    assert releases_a_stop(call("/brake/let_go"), "/brake/let_go")  # its profile's own name
    assert not releases_a_stop(call("/stop")) and not releases_a_stop(call("/brake/let_go"))


def test_a_press_is_never_undone_by_its_own_late_record_after_a_release(tmp_path):
    """The database's latch names its press: one made before a release latches nothing."""
    store = Store(tmp_path / "a.db")
    pressed = time.time()
    store.release_estop("console", pressed + 0.3)  # released 0.3 s after the press
    assert not store.latch_estop("estop", pressed)  # the press's late step
    assert store.estop_latch() is None
    assert store.latch_estop("estop", pressed + 1.0)  # a new press holds again
    store.release_robot("/tb3_1", "console", pressed + 0.3)
    assert not store.latch_robot("/tb3_1", "estop", pressed)
    assert store.latch_robot("/tb3_1", "estop", pressed + 1.0)
    store.close()


# --- on real DDS, stations in processes of their own -------------------------------------------


def _station(tmp_path: Path, name: str):
    """A station's command line: its own database and settings folder."""
    home = tmp_path / name
    home.mkdir(exist_ok=True)
    env = {
        **os.environ,
        "ASTIOP_CONFIG": str(home / "config.toml"),
        "XDG_CONFIG_HOME": str(home),
        "ASTIOP_ROBOT__ROS2_TRANSPORT": "rclpy",
    }
    cli = [sys.executable, "-m", "astiop", "--db", str(home / f"{name}.db"), "--robot", "ros2"]
    return cli, env


def _run(station, *args: str, timeout: float = 90, env: dict | None = None):
    cli, base = station
    return subprocess.run(
        [*cli, *args], capture_output=True, text=True, timeout=timeout, env={**base, **(env or {})}
    )


@pytest.mark.slow
@pytest.mark.ros
def test_a_press_at_one_station_holds_every_station_and_one_started_later(tmp_path):
    from tests.ros import require_ros, ros_client, tb3_node

    require_ros()
    from geometry_msgs.msg import TwistStamped

    a, b, c = (_station(tmp_path, n) for n in "abc")
    with tb3_node(speed=4.0), ros_client("watcher") as client:
        sent = client.collect(TwistStamped, "/cmd_vel")
        cli, env = b
        publish = subprocess.Popen(
            [*cli, "exec", "--yes", STAMPED_PUB],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        try:
            moving = until(lambda: any(m.twist.linear.x > 0.04 for _, m in sent), 60)
            assert moving, publish.poll() is not None and publish.communicate()
            pressed = _run(a, "estop", env={"ASTIOP_ROBOT__ESTOP_KEEPER": "true"})
            assert pressed.returncode == 0, pressed.stdout + pressed.stderr
            keeper = re.search(r"keeper pid (\d+)", pressed.stderr)
            assert keeper, pressed.stderr
            _, err = publish.communicate(timeout=20)
        finally:
            if publish.poll() is None:
                publish.kill()
        # station B's publish, in another process on another database, was ended
        assert publish.returncode == 1 and "E-STOP ended it" in err, err
        ended = time.monotonic()
        time.sleep(1.0)
        assert not [m for t, m in sent if t > ended and m.twist.linear.x > 0.0]
        # B's next goal, and a station C started only now, are refused from their first command
        for station in (b, c):
            out = _run(station, "exec", "--yes", GOAL)
            assert out.returncode == 2 and "E-STOP is engaged" in out.stderr, out.stderr
        # released where it was pressed: every station moves again, and the keeper is gone
        released = _run(a, "estop", "--release", "--yes")
        assert released.returncode == 0 and "E-STOP released" in released.stdout, released
        pid = int(keeper[1])
        assert until(lambda: not _alive(pid), 15), "the keeper outlived the release"
        out = _run(c, "exec", "--yes", STAMPED_PUB.replace("-t 290", "-t 3"))
        assert out.returncode == 0, out.stderr


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie: its parent (the `astiop estop` that started it) has ended, so `init` reaps it
    with open(f"/proc/{pid}/stat") as fh:
        return fh.read().split(") ")[1][0] != "Z"


def _robot_holds(client) -> bool:
    """Whether the ASTIbot's own stop holds it: a conveyor job asked of it at the dock is refused
    as latched (not held, it is refused as not at a conveyor station: nothing moves either way)."""
    from std_srvs.srv import Trigger

    answer = client.call(Trigger, "/conveyor/unload", Trigger.Request())
    return "latched" in answer.message or "e-stopped" in answer.message


def _damage(db: Path) -> None:
    """A database whose pages are garbage past its header (PRAGMA quick_check fails)."""
    Store(db).close()
    data = bytearray(db.read_bytes())
    data[120:4096] = b"\x5a" * (4096 - 120)
    db.write_bytes(bytes(data))


@pytest.mark.slow
@pytest.mark.ros
@pytest.mark.parametrize("trouble", ["damaged", "locked"])
def test_a_database_that_cannot_be_written_never_keeps_the_stop_from_the_robot(tmp_path, trouble):
    from tests.ros import require_ros, ros_client, sim_node

    require_ros()
    station = _station(tmp_path, "a")
    db = Path(station[0][station[0].index("--db") + 1])
    holder = None
    if trouble == "damaged":
        _damage(db)
    else:
        Store(db).close()
        holder = sqlite3.connect(db, timeout=0.1)
        holder.execute("BEGIN EXCLUSIVE")  # another process's write lock, held throughout
    try:
        with sim_node(speed=1.0), ros_client() as client:
            assert not _robot_holds(client)
            t0 = time.monotonic()
            out = _run(station, "estop")
            took = time.monotonic() - t0
            assert _robot_holds(client), out.stdout + out.stderr
            assert out.returncode == 1, out.stdout + out.stderr
            assert "not latched in the database" in out.stderr, out.stderr
            assert "E-STOP engaged" in out.stdout and "latched" not in out.stdout, out.stdout
            assert took < 60, took  # never the busy timeout (10 s) per write, over and over
    finally:
        if holder is not None:
            holder.rollback()
            holder.close()


@pytest.mark.slow
@pytest.mark.ros
def test_a_release_after_a_press_is_never_undone_by_the_press_and_all_agree(tmp_path):
    """`astiop estop`, and a release from another shell while it is still under way: the
    database, the robot's own stop and the next command all say released."""
    from tests.ros import require_ros, ros_client, sim_node

    require_ros()
    station = _station(tmp_path, "a")
    cli, env = station
    with sim_node(speed=1.0), ros_client() as client:
        for delay in (0.3, 1.5):
            press = subprocess.Popen(
                [*cli, "estop"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                env=env,
            )  # fmt: skip
            time.sleep(delay)
            released = _run(station, "estop", "--release", "--yes")
            said, _ = press.communicate(timeout=60)
            assert released.returncode == 0, released.stderr
            store = Store(Path(cli[cli.index("--db") + 1]))
            assert store.estop_latch() is None, (delay, said)
            store.close()
            assert not _robot_holds(client), (delay, said, released.stdout)
            out = _run(station, "exec", "--dry-run", "ros2 service call /undock " + TRIGGER)
            # (Fast DDS prints its own errors to stdout: a shared-memory port another process
            # held is one line before astiop's)
            said = out.stdout.splitlines()
            assert out.returncode == 0 and any(s.startswith("valid") for s in said), (delay, said)


@pytest.mark.slow
@pytest.mark.ros
def test_a_hung_robot_of_the_fleet_is_named_and_stopped_once_it_resumes(tmp_path):
    """`estop --all` on a discovered fleet whose robot hangs (SIGSTOP): a new process does not
    discover it, so it is named as one that may still be moving, and a keeper stops it (its
    goal cancelled) as soon as it is back on the graph."""
    import signal

    from tests.ros import SimNode, require_ros, ros_client, tb3_node

    require_ros()
    from nav2_msgs.action import NavigateToPose
    from nav_msgs.msg import Odometry
    from rclpy.action import ActionClient

    cli, env = _station(tmp_path, "a")
    fleet = ([*cli, "--fleet", "auto"], {**env, "ASTIOP_ROBOT__ESTOP_KEEPER": "true"})
    nudge = STAMPED_PUB.replace("/cmd_vel", "/tb3_2/cmd_vel").replace("-t 290", "-t 2")
    with tb3_node(speed=4.0, namespace="/tb3_1"), ros_client("watcher") as client:
        two = SimNode(speed=4.0, robot_args=("--robot", "turtlebot3", "--namespace", "/tb3_2"))
        try:
            two.wait_ready()
            odom = client.collect(Odometry, "/tb3_2/odom")
            # driven from this station (its lease is this database's), then sent far by a client
            sent = _run(fleet, "--robot-name", "tb3_2", "exec", "--yes", nudge)
            assert sent.returncode == 0, sent.stderr
            action = ActionClient(client.node, NavigateToPose, "/tb3_2/navigate_to_pose")
            assert action.wait_for_server(timeout_sec=15)
            far = NavigateToPose.Goal()
            far.pose.header.frame_id = "map"
            far.pose.pose.position.x, far.pose.pose.position.y = 28.0, 4.0
            far.pose.pose.orientation.w = 1.0
            assert client.result(action.send_goal_async(far)).accepted
            assert until(lambda: odom and abs(odom[-1][1].twist.twist.linear.x) > 0.05, 30)
            os.kill(two.proc.pid, signal.SIGSTOP)
            out = _run(fleet, "estop", "--all")
            assert out.returncode == 1, out.stdout + out.stderr
            assert "tb3_1: E-STOP engaged" in out.stdout, out.stdout
            assert "tb3_2: NOT FOUND" in out.stderr and "MAY STILL BE MOVING: tb3_2" in out.stderr
            keeper = re.search(
                r"held on tb3_2's graph until released \(keeper pid (\d+)\)", out.stderr
            )
            assert keeper, out.stderr
            os.kill(two.proc.pid, signal.SIGCONT)
            resumed = time.monotonic()
            assert until(lambda: odom[-1][0] > resumed, 30), "tb3_2 never came back"
            assert until(lambda: abs(odom[-1][1].twist.twist.linear.x) < 0.01, 30), (
                "the keeper did not stop the robot that resumed"
            )
            released = _run(fleet, "estop", "--release", "--all", "--yes")
            assert released.returncode == 0, released.stderr
            assert until(lambda: not _alive(int(keeper[1])), 15), "the keeper outlived the release"
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.kill(two.proc.pid, signal.SIGCONT)
            two.stop()
