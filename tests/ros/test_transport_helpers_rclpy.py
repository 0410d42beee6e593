"""The rclpy transport's helpers, each built alone on this process's rclpy node and handed what it
uses (no backend, no robot program): a test's own node stands for the robot, under a namespace of
the test's own."""

from __future__ import annotations

import threading
import time
import uuid

import pytest

from astiop.ros2.profile import ProfileSpec
from astiop.ros2.validation import validate
from astiop.transports.base import BackendError
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import HELD, InFlight
from astiop.transports.live_catalog import LiveGraph, describe_graph
from tests.ros import require_ros, ros_client, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]
TWIST = {"linear": {"x": 0.2, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


class Parts:
    """What a backend hands its helpers: the process, the graph, in-flight work, events."""

    def __init__(self):
        require_ros()
        from astiop.transports.rclpy.node import ros_process

        self.ns = f"/h{uuid.uuid4().hex[:8]}"  # this test's robot, alone on the graph
        ns = self.ns
        lists = {
            "topic": [
                (f"{ns}/cmd_vel", "geometry_msgs/msg/Twist"),
                (f"{ns}/robot_status", "astiop_msgs/msg/RobotStatus"),
                (f"{ns}/robot_pose", "geometry_msgs/msg/Pose2D"),
                (f"{ns}/odom", "nav_msgs/msg/Odometry"),
                (f"{ns}/battery_status", "sensor_msgs/msg/BatteryState"),
            ],
            "service": [
                (f"{ns}/stop", "std_srvs/srv/Trigger"),
                (f"{ns}/release", "std_srvs/srv/Trigger"),
            ],
            "action": [],
            "node": [(f"{ns}/astibot_base", "")],
            "param": [],
        }
        fixed = ProfileSpec(namespace=ns)
        self.proc = ros_process()
        self.live = LiveGraph(describe_graph(lists, fixed), fixed, lists)
        self.inflight, self.events = InFlight(), EventLog(0.0)
        self.closed = threading.Event()
        self.wanted: list[str] = []

    def teleop(self):
        from astiop.transports.rclpy.teleop import RclpyTeleop

        return RclpyTeleop(
            self.proc, self.live, self.inflight, self.events, self.closed, self.wanted.append
        )


@pytest.fixture
def parts():
    p = Parts()
    yield p
    p.closed.set()


def test_teleop_repeats_the_held_velocity_then_one_zero_and_the_estop_refuses_the_next_key(parts):
    from geometry_msgs.msg import Twist

    teleop = parts.teleop()
    threading.Thread(target=teleop.loop, daemon=True).start()
    with ros_client() as robot:
        got = robot.collect(Twist, f"{parts.ns}/cmd_vel")
        pub = teleop.publisher()[0]
        assert until(lambda: pub.get_subscription_count() >= 1, 10)
        teleop.drive(TWIST)
        assert parts.inflight.busy  # teleop's hold is a job the E-STOP ends
        assert parts.wanted == [f"{parts.ns}/odom"]  # its velocity watched while it drives
        assert until(lambda: not parts.inflight.busy, 5), "the hold lapses"
        assert until(lambda: got and got[-1][1].linear.x == 0.0, 3), "then one zero Twist"
        assert sum(m.linear.x == 0.2 for _, m in got) >= 3  # repeated at 10 Hz until then
        parts.inflight.stop_all()
        with pytest.raises(BackendError, match=HELD):
            teleop.drive(TWIST)
        teleop.close()


def test_the_estop_ends_what_runs_then_sends_zero_twists_and_calls_stop(parts):
    from geometry_msgs.msg import Twist
    from std_srvs.srv import Trigger

    from astiop.transports.rclpy.estop import RclpyEstop

    calls: list[str] = []

    def served(name: str):
        def answer(_request, response):
            calls.append(name)
            response.success = True
            return response

        return answer

    teleop = parts.teleop()
    estop = RclpyEstop(
        parts.proc, parts.live, parts.inflight, parts.events, 5.0, teleop, parts.closed
    )
    with ros_client() as robot:
        got = robot.collect(Twist, f"{parts.ns}/cmd_vel")
        for name in ("stop", "release"):
            robot.node.create_service(Trigger, f"{parts.ns}/{name}", served(name))
        ended: list[str] = []
        job = parts.inflight.start("a timed publish", lambda: ended.append("publish"))
        assert until(lambda: teleop.publisher()[0].get_subscription_count() >= 1, 10)
        assert estop.estop() == []
        assert ended == ["publish"] and job.ended_by_estop and parts.inflight.held
        assert estop.settle(5.0) == []
        assert calls == ["stop"]
        assert until(lambda: len(got) >= 5, 5), "a burst of zero Twists"
        assert all(m.linear.x == 0.0 and m.angular.z == 0.0 for _, m in got)
        assert estop.release() == []
        assert calls == ["stop", "release"] and not parts.inflight.held
        estop.close()
        teleop.close()


def test_state_topics_are_watched_once_published_and_odometry_only_while_wanted(parts):
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import BatteryState

    from astiop.transports.rclpy.state_watches import RclpyStateWatches

    watching = RclpyStateWatches(
        parts.proc, parts.live, parts.closed, lambda *_: None, lambda *_: None
    )
    battery, odom = f"{parts.ns}/battery_status", f"{parts.ns}/odom"
    with ros_client() as robot:
        watching.watch_state_topics()
        assert battery not in watching.watches  # nothing publishes it yet
        pubs = [robot.node.create_publisher(BatteryState, battery, 10)]
        pubs.append(robot.node.create_publisher(Odometry, odom, 10))
        assert until(lambda: parts.proc.node.get_publishers_info_by_topic(odom), 10)
        assert until(lambda: parts.proc.node.get_publishers_info_by_topic(battery), 10)
        watching.watch_state_topics()
        assert battery in watching.watches and odom not in watching.watches
        watching.want(odom)
        assert watching.poke.is_set()  # the graph thread subscribes it, not the caller
        watching.watch_state_topics()
        assert odom in watching.watches

        def heard() -> bool:  # published until the watch has matched and taken one
            pubs[0].publish(BatteryState(percentage=0.5))
            return (watching.watches[battery].latest() or {}).get("percentage") == 0.5

        assert until(heard, 5, step=0.2)
        watching.close()
        assert watching.watches == {}


def test_the_verbs_transport_publishes_and_is_refused_while_the_estop_holds(parts):
    from geometry_msgs.msg import Twist

    from astiop.transports.goal_ends import GoalEnds
    from astiop.transports.rclpy.state_watches import RclpyStateWatches
    from astiop.transports.rclpy.verbs import RclpyVerbs

    teleop = parts.teleop()
    watching = RclpyStateWatches(
        parts.proc, parts.live, parts.closed, lambda *_: None, lambda *_: None
    )
    verbs = RclpyVerbs(
        parts.proc, parts.live, parts.inflight, parts.events, watching, teleop,
        GoalEnds(parts.events),
    )  # fmt: skip
    assert verbs.graph("service") == parts.live.lists["service"]
    twist = '"{linear: {x: 0.1}}"'
    text = f"ros2 topic pub -r 10 -t 3 {parts.ns}/cmd_vel geometry_msgs/msg/Twist {twist}"
    checked = validate(text, parts.live.catalog)
    assert checked.valid, checked.reason
    with ros_client() as robot:
        got = robot.collect(Twist, f"{parts.ns}/cmd_vel")
        out, values = verbs.execute(checked, 10.0)
        assert values["published"] == 3 and "publishing #3" in out
        assert until(lambda: any(m.linear.x == 0.1 for _, m in got), 5)
        parts.inflight.stop_all()
        with pytest.raises(BackendError, match=HELD):
            verbs.execute(checked, 10.0)
        teleop.close()


def test_a_control_topic_answers_a_newcomer_and_an_asker_with_its_last_word(parts):
    """A late joiner's history is not always handed over on a loaded machine: a station's word
    is said again to each newcomer's first word and to each word marked `asking` (a reader with
    no history of its own hears only those answers)."""
    import json

    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    from astiop.transports.rclpy.control_topic import ESTOP, QOS, ControlTopic

    keeper = ControlTopic(parts.proc, parts.ns, ESTOP)
    keeper.announce({"token": "keeper", "press": {"at": 1.0}})
    name = f"{parts.ns}/{ESTOP}"
    fresh_only = QoSProfile(
        depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
    )
    try:
        with ros_client("newcomer") as newcomer:
            got = newcomer.collect(String, name, fresh_only)
            pub = newcomer.node.create_publisher(String, name, QOS)
            assert until(lambda: keeper._pub.get_subscription_count() >= 2, 10)  # noqa: SLF001
            assert until(lambda: pub.get_subscription_count() >= 1, 10)

            def answers() -> int:
                return sum(json.loads(m.data)["token"] == "keeper" for _, m in got)

            pub.publish(String(data=json.dumps({"token": "new"})))
            assert until(lambda: answers() == 1, 10), "a newcomer's first word was not answered"
            time.sleep(0.5)
            pub.publish(String(data=json.dumps({"token": "new"})))  # heard before: no answer
            pub.publish(String(data=json.dumps({"token": "new", "asking": True})))
            assert until(lambda: answers() == 2, 10), "a word asking was not answered"
            time.sleep(1.0)
            assert answers() == 2
            word = json.loads(next(m.data for _, m in got if "keeper" in m.data))
            assert word["press"] == {"at": 1.0} and word["node"] == keeper._me  # noqa: SLF001
    finally:
        keeper.close()
