"""The emulated `ros2` over DDS in parts, each built alone on one rclpy node (no server, no
socket to a client): its graph reads, its topic I/O and its calls, against a test node that
publishes, listens, serves a service and an action."""

from __future__ import annotations

import pytest

from tests.ros import require_ros, ros_client, until
from tests.unit.test_emulated_helpers import Client, run

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def ros():
    """The helpers' node (the emulated daemon's) and a test node that plays the robot."""
    require_ros()
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionServer
    from std_msgs.msg import String
    from std_srvs.srv import SetBool

    from astiop.robot_programs.emulated_cli.dds import DdsNode

    helpers = DdsNode()
    with ros_client("emulated_helpers_robot") as robot:
        node = robot.node
        chatter = node.create_publisher(String, "/chatter", 10)
        node.create_publisher(String, "/_hidden_chatter", 10)
        node.create_timer(0.1, lambda: chatter.publish(String(data="hello")))
        heard = robot.collect(String, "/heard")

        def set_flag(request, response):
            response.success, response.message = request.data, "set"
            return response

        node.create_service(SetBool, "/set_flag", set_flag)

        def navigate(handle):
            handle.succeed()
            return NavigateToPose.Result()

        server = ActionServer(node, NavigateToPose, "/navigate_test", navigate)
        try:
            yield helpers, heard
        finally:
            server.destroy()
            helpers.close()


@pytest.fixture
def graph(ros):
    from astiop.robot_programs.emulated_cli.dds_query import DdsGraph

    graph = DdsGraph(ros[0].node)
    assert until(lambda: "/emulated_helpers_robot" in graph.nodes(False), 20), graph.nodes(True)
    assert until(lambda: "/chatter" in dict(graph.topics(False)), 20), graph.topics(True)
    return graph


def test_the_graph_reads_leave_hidden_names_out_unless_asked(graph):
    assert dict(graph.topics(False))["/chatter"] == ["std_msgs/msg/String"]
    assert "/_hidden_chatter" not in dict(graph.topics(False))
    assert until(lambda: "/_hidden_chatter" in dict(graph.topics(True)), 20)
    assert "/_ros2cli_daemon_emulated" not in graph.nodes(False)
    assert "/_ros2cli_daemon_emulated" in graph.nodes(True)
    assert until(lambda: "/set_flag" in dict(graph.services(False)), 20)
    assert ("/chatter", "std_msgs/msg/String") in graph.graph("topic")
    assert ("/emulated_helpers_robot", "") in graph.graph("node")
    with pytest.raises(RuntimeError, match="does not list actions"):
        graph.graph("action")


def test_topic_echo_and_pub_on_the_node_they_are_given(ros, graph):
    from astiop.robot_programs.emulated_cli.dds_topics import DdsTopics

    helpers, heard = ros
    topics = DdsTopics(helpers.node, graph, "jazzy")
    echo = {"topic_name": "/chatter", "once": True, "timeout": 20}
    assert run(topics._topic_echo, echo) == ("data: hello\n---\n", "", 0)
    assert run(topics._topic_echo, {"topic_name": "/chatter", "field": "."}) == (
        "",
        "Invalid field value '.'\n",
        1,
    )
    pub = {"topic_name": "/heard", "message_type": "std_msgs/msg/String", "values": "{data: hi}",
           "times": 1, "rate": 10.0, "keep_alive": 0.5}  # fmt: skip
    out, err, code = run(topics._topic_pub, pub)
    assert out.endswith(
        "publisher: beginning loop\npublishing #1: std_msgs.msg.String(data='hi')\n\n"
    )
    assert (err, code) == ("", 0)
    assert until(lambda: [m.data for _, m in heard] == ["hi"], 10), heard


def test_topic_hz_reports_the_rate_until_sigint(ros, graph):
    from astiop.robot_programs.emulated_cli.call import Interrupted
    from astiop.robot_programs.emulated_cli.dds_topics import DdsTopics

    topics = DdsTopics(ros[0].node, graph, "jazzy")
    client = Client()
    client.interrupt_once_printed()
    with pytest.raises(Interrupted):
        topics._topic_hz(client.call, {"topic_name": "/chatter", "window_size": 10000})
    out, err, _ = client.result(2)
    assert out.startswith("average rate: ") and "\tmin: " in out and " window: " in out, out
    assert err == ""


def test_a_service_call_and_a_goal_on_the_node_they_are_given(ros):
    from astiop.robot_programs.emulated_cli.dds_calls import DdsCalls

    calls = DdsCalls(ros[0].node)
    request = {"service_type": "std_srvs/srv/SetBool", "service_name": "/set_flag",
               "values": "{data: true}"}  # fmt: skip
    out, err, code = run(calls._service_call, request)
    assert out.endswith(
        "requester: making request: std_srvs.srv.SetBool_Request(data=True)\n\n"
        "response:\nstd_srvs.srv.SetBool_Response(success=True, message='set')\n\n"
    ), out
    assert (err, code) == ("", 0)
    wrong = {"service_type": "std_srvs/srv/NoSuch", "service_name": "/set_flag"}
    with pytest.raises(RuntimeError, match="The passed service type is invalid"):
        run(calls._service_call, wrong)
    goal = {"action_type": "nav2_msgs/action/NavigateToPose", "action_name": "/navigate_test",
            "goal": "{}"}  # fmt: skip
    out, err, code = run(calls._action_send_goal, goal)
    assert out.startswith("Waiting for an action server to become available...\nSending goal:\n")
    assert "Goal accepted with ID: " in out and out.endswith(
        "Goal finished with status: SUCCEEDED\n"
    )
    assert (err, code) == ("", 0)


def test_the_server_runs_every_verb_its_classes_declare(ros):
    from astiop.robot_programs.emulated_cli.dds import DdsRos2

    server = DdsRos2("jazzy")
    try:
        assert server.verbs.keys() == DdsRos2.VERBS
        assert server.verbs.handler(("topic", "echo")).__self__ is server.topic_verbs
        assert server.verbs.handler(("service", "call")).__self__ is server.call_verbs
        assert server.verbs.handler(("node", "list")).__self__ is server
    finally:
        server.ros.close()
