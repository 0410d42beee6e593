"""rclpy as a transport the verbs run on (ros2/verbs/transport.py): the graph, messages, a
topic's arrivals, publishing, service calls, goals and parameters in process, printed as ros2cli
prints them (jazzy branch: ros2topic/verb/{pub,hz,bw}.py, ros2service/verb/call.py,
ros2action/verb/send_goal.py, ros2node/api, ros2param/verb/{get,set}.py)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from rclpy.action import ActionClient
from rclpy.action.client import ClientGoalHandle
from rclpy.qos import qos_profile_sensor_data

from astiop.ros2.message_objects import MessageTypeError, interface_class, to_dict, to_message
from astiop.ros2.printing import ros2cli_yaml
from astiop.ros2.render import STAMPED
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.transport import Sample
from astiop.transports.base import (
    BackendError,
    actuating,
    command_of,
    harmless,
    interface_of,
    message_of,
    name_of,
)
from astiop.transports.event_log import EventLog
from astiop.transports.goal_ends import GoalEnds
from astiop.transports.inflight import ENDED, InFlight, Job
from astiop.transports.live_catalog import LiveGraph
from astiop.transports.rclpy.graph import (
    full_name,
    latched,
    matched_qos,
    node_sections,
    read_params,
)
from astiop.transports.rclpy.node import RosProcess, RosTimeout
from astiop.transports.rclpy.state_watches import RclpyStateWatches
from astiop.transports.rclpy.teleop import RclpyTeleop

# action_msgs/msg/GoalStatus -> send_goal.py's _goal_status_to_string
STATUS = {
    1: "ACCEPTED",
    2: "EXECUTING",
    3: "CANCELING",
    4: "SUCCEEDED",
    5: "CANCELED",
    6: "ABORTED",
}
PARAM_FIELDS = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value"}


class RclpyVerbs:
    """The transport the verbs run on in this process: the graph as `live` last read it, the
    state topics' `watching` for an echo, teleop's velocity publisher for /cmd_vel. It owns the
    goals it sent, followed to their end, and how the last one ended."""

    def __init__(
        self,
        proc: RosProcess,
        live: LiveGraph,
        inflight: InFlight,
        events: EventLog,
        watching: RclpyStateWatches,
        teleop: RclpyTeleop,
        goal_ends: GoalEnds,
    ):
        self.proc = proc
        self.live = live
        self.inflight = inflight
        self.events = events
        self.watching = watching
        self.teleop = teleop
        self.goals: list[ClientGoalHandle] = []  # goals this process sent that have not ended
        self.last_outcome: str | None = None  # how the last goal ended ("succeeded", ...)
        self.goal_ends = goal_ends  # the goals sent here, not said as another client's

    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        try:
            with actuating(self.inflight, checked):  # refused while the E-STOP holds, ended by it
                return VERBS[command_of(checked).key].run(self, checked, timeout)
        except RosTimeout as exc:
            raise BackendError(str(exc)) from None
        except MessageTypeError as exc:
            raise BackendError(str(exc)) from None

    # -- the graph ------------------------------------------------------------------------
    def graph(self, kind: str) -> list[tuple[str, str]]:
        return self.live.lists[kind]

    def endpoint_counts(self, topic: str) -> tuple[int, int]:
        return self.proc.node.count_publishers(topic), self.proc.node.count_subscribers(topic)

    def action_servers(self, action: str) -> list[str]:
        from rclpy.action import get_action_server_names_and_types_by_node

        return [
            full_name(ns, n)
            for n, ns in self.proc.node.get_node_names_and_namespaces()
            if any(
                a == action
                for a, _ in get_action_server_names_and_types_by_node(self.proc.node, n, ns)
            )
        ]

    def node_info(self, target: str) -> dict[str, list[tuple[str, str]]]:
        return node_sections(self.proc.node, target)

    def interfaces(self) -> list[str]:
        raise BackendError(
            "ros2 interface list is not served through rclpy (the CLI transport, "
            "--ros2-transport cli, runs it)"
        )

    # -- topics -----------------------------------------------------------------------------
    def take(self, c: Checked, timeout: float) -> dict[str, Any]:
        name = name_of(c)
        w = self.watching.watches.get(name)
        spec = self.live.catalog.topics.get(name)
        if w is not None and spec is not None and spec.rate_hz > 0:
            # the robot's last publication, if it came within one period, is the message
            # `ros2 topic echo --once` would print next (one period newer at most)
            msg = w.current(1.0 / spec.rate_hz) or w.next_message(timeout)
        elif w is not None and latched(self.proc, name) and w.latest_object() is not None:
            msg = w.latest_object()  # what a new subscription is handed at once (/amcl_pose)
        elif w is not None:
            msg = w.next_message(timeout)
        else:
            msg = self._one_message(name, interface_of(c), timeout)
        if msg is None:
            raise BackendError(f"no reading from {name} in {timeout:g} s")
        return to_dict(msg)

    def _one_message(self, name: str, type_: str, timeout: float) -> Any:
        from astiop.transports.rclpy.watch import TopicWatch

        w = TopicWatch(self.proc, name, type_)
        try:
            return w.next_message(timeout) or w.latest_object()
        finally:
            w.close()

    def samples(
        self, topic: str, type_: str, enough: Callable[[list[Sample]], bool], timeout: float
    ) -> list[Sample]:
        """Each message's arrival and its serialized size (taken raw, as ros2 topic bw does)."""
        got: list[Sample] = []

        def arrived(data: Any) -> None:  # bytes: raw=True (rclpy's annotation says a message)
            got.append((time.monotonic(), len(data)))

        sub = self.proc.node.create_subscription(
            interface_class(type_), topic, arrived, qos_profile_sensor_data, raw=True
        )
        deadline = time.monotonic() + timeout
        try:
            while time.monotonic() < deadline and not enough(list(got)):
                time.sleep(0.05)
        finally:
            self.proc.node.destroy_subscription(sub)
        return list(got)

    # -- actuation ---------------------------------------------------------------------------
    def publish(self, c: Checked, timeout: float) -> tuple[str, Any]:
        cmd, name = command_of(c), name_of(c)
        times = 1 if "once" in cmd.flags else cmd.options.get("times", 1)
        rate = cmd.options.get("rate", 1.0)
        message = message_of(c)
        if name == "/cmd_vel":
            pub, cls, type_ = self.teleop.publisher()
            twist = message["twist"] if type_ == STAMPED else message
            self.teleop.replaced()
        else:
            cls = interface_class(interface_of(c))
            pub = self.proc.node.create_publisher(cls, name, matched_qos(self.proc, name))
        lines = []
        job = self.inflight.current(f"publish on {name}")
        try:
            if pub.get_subscription_count() < 1:
                lines.append("Waiting for at least 1 matching subscription(s)...")
                deadline = time.monotonic() + timeout
                while pub.get_subscription_count() < 1:
                    if time.monotonic() > deadline:
                        raise BackendError(f"no subscriber on {name} within {timeout:g} s")
                    if job.wait(0.1):
                        raise BackendError(f"{ENDED}: nothing was published")
            lines.append("publisher: beginning loop")
            for i in range(times):
                if i and job.wait(1.0 / rate):
                    raise BackendError(f"{ENDED} after {i} of {times} messages")
                msg = (
                    self.teleop.stamped(cls, message)
                    if name == "/cmd_vel"
                    else to_message(cls, message)
                )
                with job.sending():
                    pub.publish(msg)
                lines += [f"publishing #{i + 1}: {msg!r}", ""]
        finally:
            if name != "/cmd_vel":
                self.proc.node.destroy_publisher(pub)
        values: dict[str, Any] = {"published": times}
        if name == "/cmd_vel":
            values["twist"] = twist
        return "\n".join(lines) + "\n", values

    def call(self, c: Checked, timeout: float) -> tuple[str, Any]:
        name = name_of(c)
        srv: Any = interface_class(interface_of(c))  # generated: its Request is not typed
        request = to_message(srv.Request, c.message or {})
        client = self.proc.client(srv, name)
        lines = []
        if not client.service_is_ready():
            lines.append("waiting for service to become available...")
            if not client.wait_for_service(timeout_sec=timeout):
                raise BackendError(f"service {name} is not available (waited {timeout:g} s)")
        lines.append(f"requester: making request: {request!r}\n")
        again = harmless(c)  # a read, a stop, a cancel
        response = self.proc.ask(client, request, timeout, f"service {name}", again=again)
        lines.append(f"response:\n{response!r}\n")
        if c.local_name == "/stop":
            self.cancel_goals()
        return "\n".join(lines) + "\n", to_dict(response)

    def send_goal(self, c: Checked, timeout: float) -> tuple[str, Any]:
        """Return at acceptance; the goal is followed to its end in the background."""
        name = name_of(c)
        action: Any = interface_class(interface_of(c))  # generated: its Goal is not typed
        goal = to_message(action.Goal, c.message or {})
        client = ActionClient(self.proc.node, action, name)
        lines = ["Waiting for an action server to become available..."]
        if not client.wait_for_server(timeout_sec=timeout):
            client.destroy()
            raise BackendError(f"no action server for {name} within {timeout:g} s")
        lines.append(f"Sending goal:\n     {ros2cli_yaml(to_dict(goal))}")
        future = client.send_goal_async(goal)  # its feedback is not shown: it returns here
        try:
            handle = self.proc.wait(future, timeout, f"{name} goal")
        except RosTimeout:
            client.destroy()
            raise
        if not handle.accepted:
            client.destroy()
            lines.append("Goal was rejected.")
            return "\n".join(lines) + "\n", {"accepted": False, "status": "REJECTED"}
        goal_id = bytes(handle.goal_id.uuid).hex()
        self.goal_ends.sent.append(goal_id)  # its end is said with its result, not as another's
        try:  # followed as a job of its own until it ends: the E-STOP cancels it
            job = self.inflight.start(f"goal {name}", handle.cancel_goal_async, name)
        except BackendError:
            handle.cancel_goal_async()  # the E-STOP came while it was being accepted
            raise BackendError(f"{ENDED}: the goal was accepted and canceled") from None
        lines.append(f"Goal accepted with ID: {goal_id}\n")
        self.goals.append(handle)
        self.last_outcome = None
        handle.get_result_async().add_done_callback(
            lambda f: self._goal_ended(handle, client, f, job)
        )
        return "\n".join(lines) + "\n", {"accepted": True, "goal_id": goal_id, "status": "ACCEPTED"}

    def _goal_ended(self, handle: Any, client: Any, future: Any, job: Job) -> None:
        job.done()
        if handle in self.goals:
            self.goals.remove(handle)
        result = future.result()
        status = STATUS.get(result.status, "UNKNOWN") if result is not None else "UNKNOWN"
        self.last_outcome = status.lower()
        why = getattr(result.result, "error_msg", "") if result is not None else ""
        severity = "info" if status == "SUCCEEDED" else "warning"
        self.events.add("goal", severity, f"goal finished: {status}" + (f" ({why})" if why else ""))
        client.destroy()

    def cancel_goals(self) -> None:
        for handle in list(self.goals):
            handle.cancel_goal_async()

    # -- parameters ----------------------------------------------------------------------------
    def list_params(self, named: str | None, timeout: float) -> list[tuple[str, str, str]]:
        # asked of each node now, as ros2cli does (ros2param/verb/list.py)
        served = {n for n, _ in self.live.lists["service"]}
        nodes = [n for n, _ in self.live.lists["node"] if f"{n}/list_parameters" in served]
        read = read_params(self.proc, [named] if named else nodes, timeout)
        return [(*_node_and_name(key), type_) for key, type_ in read]

    def get_param(self, node: str, param: str, timeout: float) -> Any:
        from rcl_interfaces.srv import GetParameters

        response = self._param_call(
            GetParameters, f"{node}/get_parameters", GetParameters.Request(names=[param]), timeout
        )
        if not response.values or response.values[0].type == 0:
            raise BackendError(f"parameter {param} is not set on {node}")
        value = response.values[0]
        if value.type not in PARAM_FIELDS:
            raise BackendError(f"parameter {param} has a type astiop does not read ({value.type})")
        return getattr(value, PARAM_FIELDS[value.type])

    def set_param(self, node: str, param: str, value: Any, timeout: float) -> str:
        from rcl_interfaces.msg import Parameter, ParameterValue
        from rcl_interfaces.srv import SetParameters

        kind = {bool: 1, int: 2, float: 3, str: 4}[type(value)]
        pv = ParameterValue(type=kind, **{PARAM_FIELDS[kind]: value})
        request = SetParameters.Request(parameters=[Parameter(name=param, value=pv)])
        response = self._param_call(SetParameters, f"{node}/set_parameters", request, timeout)
        result = response.results[0]
        if not result.successful:  # ros2cli prints this and exits 0: it did not happen
            raise BackendError(
                "Setting parameter failed" + (f": {result.reason}" if result.reason else "")
            )
        return result.reason

    def _param_call(self, srv: Any, name: str, request: Any, timeout: float) -> Any:
        try:
            return self.proc.call(srv, name, request, timeout)
        except RosTimeout as exc:
            if "is not served" in str(exc):
                raise BackendError(f"{name.rsplit('/', 1)[0]}: node not found") from None
            raise


def _node_and_name(key: str) -> tuple[str, str]:
    """ "/node name", as graph.read_params keys a parameter."""
    node, name = key.split(" ", 1)
    return node, name
