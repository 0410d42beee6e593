"""One operator in control of a shared robot: the lease in the store, refused and taken over,
told to the one it was taken from; the gateway refusing motion without it and never a stop."""

from __future__ import annotations

import threading

from astiop.config import load_settings
from astiop.robot.factory import make_sim_gateway
from astiop.robot.lease import Lease, lease_key
from astiop.sim.simulator import Simulator
from astiop.store import Store
from tests.ros import until

GO = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.3}}'"
HALT = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.0}}'"
STOP = "ros2 service call /stop std_srvs/srv/Trigger"


def test_one_holder_at_a_time_and_a_takeover_is_told(tmp_path):
    key = lease_key("/astibot_2", 7)
    first, second = Store(tmp_path / "a.db"), Store(tmp_path / "a.db")  # two consoles
    mine = Lease(first, key, "astibot_2", "console")
    theirs = Lease(second, key, "astibot_2", "astiop mcp")
    try:
        assert mine.take() is None and mine.held
        refused = theirs.take()
        assert refused is not None and refused.who == "console" and not theirs.held
        assert theirs.holder().who == "console"
        told = threading.Event()
        said = []
        mine.on_lost = lambda holder: (said.append(holder), told.set())
        assert theirs.take(force=True) is None and theirs.held
        assert told.wait(6), "the first holder was never told"
        assert said[0].who == "astiop mcp"
        assert not mine.held and mine.take() is not None  # taken back only by force
        theirs.release()
        assert mine.holder() is None and mine.take() is None
        # a holder not heard for the lease's time has let go (a console killed)
        first.db.conn.execute("UPDATE leases SET seen_at = seen_at - 60")
        first.db.conn.commit()
        mine._halt.set()  # its heartbeat stopped, as a killed process's
        assert theirs.take() is None
    finally:
        mine.release()
        theirs.release()
        first.close()
        second.close()


def test_motion_without_the_lease_is_refused_and_never_reaches_the_robot(tmp_path):
    store = Store(tmp_path / "b.db")
    sim = Simulator(seed=3)
    gateway = make_sim_gateway(load_settings({}, env={}), store, sim=sim)
    other = Lease(Store(tmp_path / "b.db"), "/@0", "the robot", "someone else")
    gateway.lease = Lease(store, "/@0", "the robot", "console")
    try:
        assert other.take() is None
        assert gateway.take_control() == (
            f"the robot is controlled by someone else (pid {other.pid} on {other.host})"
        )
        before = sim.body.position
        ex = gateway.run(GO, confirm=lambda _c: True)
        assert not ex.executed and "controlled by someone else" in ex.reason, ex
        assert not gateway.drive(0.3, 0.0, 0.0).executed
        sim.step(0.5)
        assert sim.body.position == before  # nothing reached the robot
        for stop in (HALT, STOP):  # anyone may stop any robot
            assert gateway.run(stop, confirm=lambda _c: True).executed, stop
        assert gateway.take_control(force=True) is None
        assert gateway.run(GO, confirm=lambda _c: True).executed
        assert until(lambda: other.holder().who == "console", 1)
    finally:
        gateway.close()
        other.release()
        other.store.close()
        store.close()


def test_a_take_under_way_when_the_lease_is_released_takes_nothing(tmp_path):
    """A console that closes while its first take is still opening the robot's graph (which
    waits for the holders there) leaves no holder behind: no row, no word, no heartbeat."""
    opening, opened = threading.Event(), threading.Event()
    said: list[dict] = []

    class Graph:  # the robot's graph, slow to open as a loaded DDS discovery is
        def __init__(self):
            opening.set()
            opened.wait(5)

        def announce(self, word, _acked_s=0.0):
            said.append(word)

        def holders(self, _released=False):
            return []

        def close(self):
            pass

    store = Store(tmp_path / "c.db")
    lease = Lease(store, "/@0", "the robot", "console", channel=Graph)
    taking = threading.Thread(target=lease.take)
    taking.start()
    assert opening.wait(5)
    lease.release()  # the console closes meanwhile
    opened.set()
    taking.join(5)
    assert not lease.held and store.lease("/@0") is None
    assert not said, said  # never announced as a holder (nor as anything: it was closed)
    assert lease._thread is None, "no heartbeat started"
    store.close()
