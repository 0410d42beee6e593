"""The emulated `ros2`'s helpers built alone, without its server: the table that finds which
method runs a verb, and the simulated robot's topic verbs on a simulator of their own. Each
verb runs on a real `Call`, over a socket pair, as the server hands it one."""

from __future__ import annotations

import json
import select
import socket
import threading
import time

import pytest

from astiop.robot_programs.emulated_cli.call import Call, Interrupted
from astiop.robot_programs.emulated_cli.topics import RobotTopics
from astiop.robot_programs.emulated_cli.verb_table import VerbTable, marked, runs, served
from astiop.ros2.catalog import astibot_catalog
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend


class Client:
    """The client's end of one call: what the verb printed on each stream, and its status."""

    def __init__(self) -> None:
        self.peer, conn = socket.socketpair()
        self.peer.sendall(b"{}\n")  # the request line: the verb's arguments come separately
        self.call = Call(conn)

    def interrupt(self) -> None:
        self.peer.sendall(b"SIGINT\n")

    def interrupt_once_printed(self, timeout: float = 30.0) -> None:
        """Ctrl-C as soon as the verb prints something (or after `timeout`), on a thread."""

        def watch() -> None:
            select.select([self.peer], [], [], timeout)  # read nothing: result() reads it all
            self.interrupt()

        threading.Thread(target=watch, daemon=True).start()

    def result(self, code: int) -> tuple[str, str, int]:
        """Ends the call with `code`; what the client read, as ros2cli would print it."""
        self.call.finish(code)
        out, err, status = [], [], None
        for line in self.peer.makefile("r", encoding="utf-8"):
            msg = json.loads(line)
            out.append(msg.get("out", ""))
            err.append(msg.get("err", ""))
            status = msg.get("exit", status)
        self.peer.close()
        return "".join(out), "".join(err), status


def run(handler, args: dict) -> tuple[str, str, int]:
    """One verb's call, ended as the servers end it: a returned string is ros2cli's error."""
    client = Client()
    code = handler(client.call, args)
    if isinstance(code, str):
        client.call.err(code + "\n")
        code = 1
    return client.result(code or 0)


# -- VerbTable ---------------------------------------------------------------------------------
class Graph:
    def __init__(self) -> None:
        self.asked = 0

    @runs("topic list", "service list")
    def listing(self, call, a):
        self.asked += 1
        return 0

    def helper(self, call, a):  # not marked: runs nothing
        return 1


class Daemon:
    @runs("daemon status")
    def status(self, call, a):
        return "down"


class LouderGraph(Graph):
    @runs("topic list")
    def listing(self, call, a):
        return 7


def test_a_verb_table_finds_each_objects_marked_methods_bound_to_it():
    graph, daemon = Graph(), Daemon()
    table = VerbTable(graph, daemon)
    assert table.keys() == {("topic", "list"), ("service", "list"), ("daemon", "status")}
    assert table.handler(("service", "list"))(None, {}) == 0 and graph.asked == 1
    assert table.handler(("daemon", "status"))(None, {}) == "down"
    assert table.handler(("topic", "echo")) is None
    assert table.handler((None, None)) is None  # a request with no command at all


def test_a_subclass_method_runs_the_verb_it_overrides():
    assert marked(LouderGraph) == {("topic", "list"): "listing", ("service", "list"): "listing"}
    assert VerbTable(LouderGraph()).handler(("topic", "list"))(None, {}) == 7


def test_two_objects_that_run_one_verb_are_refused():
    with pytest.raises(ValueError, match="ros2 topic list is run twice"):
        VerbTable(Graph(), LouderGraph())


def test_the_verbs_served_are_known_from_the_classes_alone():
    assert served([Graph, Daemon]) == VerbTable(Graph(), Daemon()).keys()


# -- RobotTopics -------------------------------------------------------------------------------
GRAPH = {
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/odom": "nav_msgs/msg/Odometry",
    "/rosout": "rcl_interfaces/msg/Log",
}
TWIST = {"linear": {"x": 0.2, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.5}}
TWIST_REPR = (
    "geometry_msgs.msg.Twist(linear=geometry_msgs.msg.Vector3(x=0.2, y=0.0, z=0.0), "
    "angular=geometry_msgs.msg.Vector3(x=0.0, y=0.0, z=0.5))"
)


@pytest.fixture
def topics(tmp_path):
    """The robot's topic verbs on a simulator and a graph of their own: no server, no robot."""
    backend = SimBackend(Simulator(seed=0), Store(tmp_path / "robot.db"), realtime=True)
    yield RobotTopics(backend, astibot_catalog(), lambda: dict(GRAPH))
    backend.close()


def test_the_robot_topics_list_type_and_info_read_the_graph_they_are_given(topics):
    assert run(topics._topic_list, {"show_types": True}) == (
        "/cmd_vel [geometry_msgs/msg/Twist]\n/odom [nav_msgs/msg/Odometry]\n"
        "/rosout [rcl_interfaces/msg/Log]\n",
        "",
        0,
    )
    assert run(topics._topic_list, {"count_topics": True}) == ("3\n", "", 0)
    assert run(topics._topic_type, {"topic_name": "/odom"}) == ("nav_msgs/msg/Odometry\n", "", 0)
    assert run(topics._topic_type, {"topic_name": "/scan"}) == ("", "", 1)  # not on this graph
    assert run(topics._topic_info, {"topic_name": "/cmd_vel"}) == (
        "Type: geometry_msgs/msg/Twist\nPublisher count: 0\nSubscription count: 1\n",
        "",
        0,
    )
    assert run(topics._topic_info, {"topic_name": "/scan"}) == ("", "Unknown topic '/scan'\n", 1)


def test_a_twist_published_drives_the_base_and_is_logged(topics):
    args = {"topic_name": "/cmd_vel", "message_type": "geometry_msgs/msg/Twist",
            "values": json.dumps(TWIST), "once": True, "rate": 1.0, "keep_alive": 0.0}  # fmt: skip
    before = time.monotonic()
    out, err, code = run(topics._topic_pub, args)
    assert (out, err, code) == (
        f"publisher: beginning loop\npublishing #1: {TWIST_REPR}\n\n",
        "",
        0,
    )
    assert topics.backend.last_twist == TWIST
    assert [e["twist"] for e in topics.cmd_vel_log] == [TWIST]
    assert topics.cmd_vel_log[0]["mono"] >= before


def test_the_robot_listens_to_cmd_vel_only(topics):
    args = {"topic_name": "/odom", "message_type": "nav_msgs/msg/Odometry", "values": "{}",
            "once": True, "rate": 1.0}  # fmt: skip
    out, err, code = run(topics._topic_pub, args)
    assert code == 1 and "only listens to /cmd_vel" in err and not topics.cmd_vel_log


def test_echo_on_cmd_vel_prints_the_twist_the_helper_receives(topics):
    echo = Client()
    codes: list[int] = []
    worker = threading.Thread(
        target=lambda: codes.append(
            topics._topic_echo(echo.call, {"topic_name": "/cmd_vel", "once": True, "timeout": 10})
        )
    )
    worker.start()
    pub = {"topic_name": "/cmd_vel", "message_type": "geometry_msgs/msg/Twist",
           "values": json.dumps(TWIST), "once": True, "rate": 1.0, "keep_alive": 0.0}  # fmt: skip
    for _ in range(25):  # published until echo, waiting from whenever it started, prints one
        run(topics._topic_pub, pub)
        worker.join(0.2)
        if not worker.is_alive():
            break
    out, err, _ = echo.result(codes[0])
    assert out.startswith("linear:\n  x: 0.2\n") and out.endswith("---\n"), out
    assert err == "" and codes == [0]


def test_echo_of_a_topic_nobody_publishes_says_so_or_waits_for_sigint(topics):
    assert run(topics._topic_echo, {"topic_name": "/scan"}) == (
        "",
        "WARNING: topic [/scan] does not appear to be published yet\n"
        "Could not determine the type for the passed topic\n",
        1,
    )
    waiting = Client()
    threading.Timer(0.2, waiting.interrupt).start()
    with pytest.raises(Interrupted):  # a hidden topic: nobody publishes it here, as on Ctrl-C
        topics._topic_echo(
            waiting.call, {"topic_name": "/rosout", "message_type": "rcl_interfaces/msg/Log"}
        )
    assert waiting.result(2) == ("", "", 2)
