"""The transports' helpers, each built alone and handed what it uses: the `ros2` transport's
commands and E-STOP over a recorded `run` (no `ros2` process), the simulator as the verbs'
transport. The rclpy ones: test_transport_helpers_rclpy.py."""

from __future__ import annotations

import threading

import pytest

from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.profile import ProfileSpec
from astiop.ros2.validation import validate
from astiop.sim.simulator import Simulator
from astiop.transports.base import BackendError
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import ENDED, HELD, InFlight
from astiop.transports.live_catalog import LiveGraph, describe_graph
from astiop.transports.ros2cli.commands import CliCommands
from astiop.transports.ros2cli.estop import CliEstop
from astiop.transports.ros2cli.process import Run
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.simulator.verbs import SimVerbs

LISTS = {
    "topic": [
        ("/cmd_vel", "geometry_msgs/msg/Twist"),
        ("/battery_status", "sensor_msgs/msg/BatteryState"),
    ],
    "service": [("/stop", "std_srvs/srv/Trigger"), ("/release", "std_srvs/srv/Trigger")],
    "action": [],
    "node": [("/astibot_base", "")],
    "param": [],
}


class RecordedRos2:
    """A `run` handed to a helper: each `ros2 ARGV` recorded, answered by `answer(argv)`."""

    def __init__(self, answer=None):
        self.argvs: list[list[str]] = []
        self.answer = answer or (lambda argv: Run(argv, stdout=["response:\n"], returncode=0))
        self._lock = threading.Lock()

    def __call__(self, argv, timeout, *, until=None, cancel=None, cancellable=None) -> Run:
        with self._lock:
            self.argvs.append(list(argv))
        return self.answer(argv)

    def ran(self, *words: str) -> list[list[str]]:
        return [a for a in self.argvs if a[: len(words)] == list(words)]


def checked(text: str):
    c = validate(text, astibot_catalog())
    assert c.valid, c.reason
    return c


def live_graph(lists=LISTS) -> LiveGraph:
    return LiveGraph(describe_graph(lists, ProfileSpec()), ProfileSpec(), lists)


# -- CliCommands ---------------------------------------------------------------------------------
def commands(run: RecordedRos2, inflight: InFlight | None = None) -> CliCommands:
    return CliCommands(run, "ros2", inflight or InFlight(), EventLog(0.0))


def test_an_echo_asks_for_one_whole_message_and_reads_its_values():
    run = RecordedRos2(lambda argv: Run(argv, stdout=["percentage: 0.5\n", "---\n"], returncode=0))
    text, values = commands(run).execute(checked("ros2 topic echo /battery_status"), 5.0)
    (argv,) = run.argvs
    assert argv[:3] == ["topic", "echo", "/battery_status"]
    assert "--once" in argv and "--full-length" in argv
    assert values["percentage"] == 0.5 and "percentage: 0.5" in text


def test_a_call_nothing_served_fails_with_its_reason():
    run = RecordedRos2(
        lambda argv: Run(
            argv, stdout=["waiting for service to become available...\n"], stopped=True
        )
    )
    with pytest.raises(BackendError, match="service /dock is not available"):
        commands(run).execute(checked("ros2 service call /dock std_srvs/srv/Trigger"), 1.0)


def test_an_actuation_is_refused_while_the_estop_holds_and_nothing_runs():
    inflight, run = InFlight(), RecordedRos2()
    inflight.stop_all()
    with pytest.raises(BackendError, match=HELD):
        commands(run, inflight).execute(
            checked("ros2 service call /dock std_srvs/srv/Trigger"), 1.0
        )
    assert run.argvs == []


def test_an_actuation_the_estop_ended_says_so():
    inflight = InFlight()

    def killed(argv):  # the E-STOP comes while `ros2` runs, and its process dies
        inflight.stop_all()
        return Run(argv, stderr=["killed\n"], returncode=-9)

    with pytest.raises(BackendError, match=ENDED):
        commands(RecordedRos2(killed), inflight).execute(
            checked("ros2 service call /dock std_srvs/srv/Trigger"), 1.0
        )
    assert not inflight.busy


# -- CliEstop ------------------------------------------------------------------------------------
def estop(run: RecordedRos2, lists=LISTS) -> tuple[CliEstop, InFlight, EventLog]:
    inflight, events = InFlight(), EventLog(0.0)
    return CliEstop(run, live_graph(lists), inflight, events, timeout_s=2.0), inflight, events


def test_the_estop_holds_then_sends_the_zero_burst_and_calls_stop():
    run = RecordedRos2()
    helper, inflight, _ = estop(run)
    assert helper.estop() == []
    assert inflight.held
    assert helper.settle(1.0) == []
    (burst,) = run.ran("topic", "pub")
    assert burst[-3:-1] == ["/cmd_vel", "geometry_msgs/msg/Twist"] and "-t" in burst
    assert run.ran("service", "call", "/stop") == [
        ["service", "call", "/stop", "std_srvs/srv/Trigger", "{}"]
    ]


def test_a_stop_call_that_fails_is_said_by_settle():
    def answer(argv):
        if argv[:2] == ["service", "call"]:
            return Run(argv, stderr=["the robot refused\n"], returncode=1)
        return Run(argv, returncode=0)

    helper, _, events = estop(RecordedRos2(answer))
    helper.estop()
    assert helper.settle(1.0) == ["E-STOP /stop: the robot refused"]
    assert [e.kind for e in events.since(0)] == ["estop"]


def test_a_robot_without_velocity_command_or_stop_is_a_failure_returned_at_once():
    nothing = {**LISTS, "topic": [], "service": []}
    helper, inflight, _ = estop(RecordedRos2(), nothing)
    failures = helper.estop()
    assert inflight.held
    assert "the robot has no velocity command: no zero Twist was sent" in failures
    assert "the robot has neither a stop service nor a navigation action" in failures


def test_release_lets_go_of_the_hold_and_of_the_robots_latch():
    run = RecordedRos2()
    helper, inflight, _ = estop(run)
    helper.estop()
    helper.settle(1.0)
    assert helper.release() == []
    assert not inflight.held
    assert run.ran("service", "call", "/release")
    before = len(run.argvs)
    helper.release(robot=False)  # another process released the robot: this one only
    assert len(run.argvs) == before


# -- SimVerbs ------------------------------------------------------------------------------------
def test_the_simulator_as_the_verbs_transport_answers_from_its_backend():
    backend = SimBackend(Simulator(seed=0))
    verbs = SimVerbs(backend)
    assert ("/cmd_vel", "geometry_msgs/msg/Twist") in verbs.graph("topic")
    assert ("/stop", "std_srvs/srv/Trigger") in verbs.graph("service")
    assert verbs.endpoint_counts("/cmd_vel") == (0, 1)
    battery = verbs.take(checked("ros2 topic echo /battery_status"), 5.0)
    assert battery["percentage"] == pytest.approx(backend.sim.battery.soc, abs=1e-3)
    assert backend.sim.t > 0.0  # it waited for the next publication on the simulator's clock
    (node,) = [n for n, p in backend.params if p == "max_linear_speed"]
    assert verbs.set_param(node, "max_linear_speed", 0.3, 1.0) == ""
    assert backend.sim.gains.v_max == 0.3 and verbs.get_param(node, "max_linear_speed", 1.0) == 0.3
    text, response = verbs.call(checked("ros2 service call /stop std_srvs/srv/Trigger"), 1.0)
    assert response["success"] and text.startswith("requester: making request:")
