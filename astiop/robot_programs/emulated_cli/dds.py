"""The emulated `ros2` over real DDS (`astiop emulate-ros2 --dds`): the same client (argv parsed
by ros2cli's argument definitions, logged to ros2.log), and behind its socket one rclpy node
that runs every verb against whatever robot is on the domain, printing what ros2cli prints. It
plays ros2cli and its daemon: the CLI transport meets a robot astiop did not write (the
TurtleBot3 program, `astiop sim node`) on real DDS.

What each verb prints follows ros2cli's humble and jazzy branches: ros2topic/verb/{list,info,
type}.py, ros2service/verb/{list,type}.py, ros2action/verb/{list,info}.py, ros2node/verb/
{list,info}.py, ros2param/verb/{list,get,set}.py, ros2cli/verb/daemon/*.py. A verb's failure
is a string on stderr and exit status 1 (ros2cli/cli.py: a returned string, a RuntimeError);
Ctrl-C is status 2 (signal.SIGINT). Only types importable in this install can be used.
"""

from __future__ import annotations

import contextlib
import functools
import os
import socket
import threading
from typing import Any, ClassVar

import rclpy
import yaml
from rclpy.action import (
    get_action_client_names_and_types_by_node,
    get_action_names_and_types,
    get_action_server_names_and_types_by_node,
)
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from astiop.native_stdout import native_output_to_stderr
from astiop.robot_programs.emulated_cli.call import Call, Interrupted
from astiop.robot_programs.emulated_cli.dds_calls import DdsCalls
from astiop.robot_programs.emulated_cli.dds_query import DdsGraph, Pairs, run_query
from astiop.robot_programs.emulated_cli.dds_topics import DdsTopics
from astiop.robot_programs.emulated_cli.verb_table import VerbKey, VerbTable, runs, served
from astiop.ros2.definitions import DEFINITIONS
from astiop.ros2.interfaces import interface_show
from astiop.ros2.printing import (
    INTERFACE_FLAGS,
    interface_list_text,
    list_text,
    node_info_text,
    param_list_text,
)
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import QUERY
from astiop.transports.rclpy.graph import full_name, node_sections, read_params
from astiop.transports.rclpy.verbs import PARAM_FIELDS

NODE_NAME = "_ros2cli_daemon_emulated"  # hidden, as the daemon's node is
# ros2param/verb/get.py's labels, by rcl_interfaces/msg/ParameterType
PARAM_LABELS = {
    1: ("Boolean value is:", "bool_value"),
    2: ("Integer value is:", "integer_value"),
    3: ("Double value is:", "double_value"),
    4: ("String value is:", "string_value"),
    5: ("Byte values are:", "byte_array_value"),
    6: ("Boolean values are:", "bool_array_value"),
    7: ("Integer values are:", "integer_array_value"),
    8: ("Double values are:", "double_array_value"),
    9: ("String values are:", "string_array_value"),
}


class DdsNode:
    """One rclpy context and node, spun on a thread; each call's entities are its own and are
    destroyed when the call ends, as a ros2cli process's node goes with it."""

    def __init__(self) -> None:
        native_output_to_stderr()
        self.context = rclpy.Context()
        rclpy.init(args=["--ros-args", "--disable-stdout-logs"], context=self.context)
        self.node = Node(NODE_NAME, context=self.context, start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._halt = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="rclpy", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._halt.is_set() and self.context.ok():
            with contextlib.suppress(Exception):
                self.executor.spin_once(timeout_sec=0.1)

    def call(self, srv_type: Any, name: str, request: Any, timeout: float) -> Any:
        """One service call with a client of its own (read_params' `proc.call`)."""
        client = self.node.create_client(srv_type, name)
        try:
            if not client.wait_for_service(timeout_sec=timeout):
                raise TimeoutError(f"{name} is not served")
            done = threading.Event()
            future = client.call_async(request)
            future.add_done_callback(lambda _f: done.set())
            if not done.wait(timeout):
                raise TimeoutError(f"{name}: no answer within {timeout:g} s")
            return future.result()
        finally:
            self.node.destroy_client(client)

    def close(self) -> None:
        self._halt.set()
        self._thread.join(2.0)
        with contextlib.suppress(Exception):
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
            rclpy.shutdown(context=self.context)


def print_listing(call: Call, pairs: Pairs, a: dict, count_flag: str) -> int:
    """A `... list` verb's lines: each name, its types with -t, the count alone with -c."""
    flags = {k for k in ("show_types", count_flag) if a.get(k)}
    call.out(list_text([(n, ", ".join(t)) for n, t in pairs], flags)[0])
    return 0


class DdsRos2:
    """The server: the graph, node, interface, param and daemon verbs itself, the topic I/O
    and the calls by helpers on the same node, all found through one VerbTable."""

    VERBS: ClassVar[frozenset[VerbKey]]  # every verb it runs, known without a node

    def __init__(self, distro: str):
        self.distro = distro
        self.daemon_running = True
        self.ros = DdsNode()
        self.node = self.ros.node
        self.graph = DdsGraph(self.node)
        self.topic_verbs = DdsTopics(self.node, self.graph, distro)
        self.call_verbs = DdsCalls(self.node)
        self.verbs = VerbTable(self, self.topic_verbs, self.call_verbs)

    # -- serving ----------------------------------------------------------------------------
    def serve(self, path: str) -> None:
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        if os.path.exists(path):
            os.unlink(path)
        server.bind(path)
        server.listen(64)
        try:
            while True:
                conn, _ = server.accept()
                threading.Thread(target=self._handle, args=(conn,), daemon=True).start()
        finally:
            server.close()
            self.ros.close()

    def _handle(self, conn: socket.socket) -> None:
        call = Call(conn)
        args = call.request.get("args", {})
        key = (args.get("command"), args.get("verb"))
        handler = self.verbs.handler(key)
        if handler is None and key in VERBS and VERBS[key].runs_as == QUERY:
            argv = call.request.get("argv", [])
            handler = functools.partial(run_query, self.graph, self.distro, argv=argv)
        code = 1
        try:
            if handler is None:
                call.err(f"the emulated ros2 does not run ros2 {args.get('command')} "
                         f"{args.get('verb')} over DDS\n")  # fmt: skip
            else:
                rc = handler(call, args)
                if isinstance(rc, str):  # ros2cli prints a returned string and exits 1
                    call.err(rc + "\n")
                    rc = 1
                code = rc or 0
        except Interrupted:
            code = 2  # ros2cli returns signal.SIGINT on KeyboardInterrupt
        except Exception as exc:  # noqa: BLE001 - ros2cli prints a RuntimeError; the server lives
            with contextlib.suppress(Interrupted):
                call.err(f"{exc}\n" if isinstance(exc, RuntimeError) else f"{exc!r}\n")
        call.finish(code)

    # -- the graph --------------------------------------------------------------------------
    @runs("topic list")
    def _topic_list(self, call: Call, a: dict):
        if a.get("verbose"):
            return "the emulated ros2 does not print topic list --verbose"
        pairs = self.graph.topics(a.get("include_hidden_topics"))
        return print_listing(call, pairs, a, "count_topics")

    @runs("service list")
    def _service_list(self, call: Call, a: dict):
        pairs = self.graph.services(a.get("include_hidden_services"))
        return print_listing(call, pairs, a, "count_services")

    @runs("action list")
    def _action_list(self, call: Call, a: dict):
        pairs = get_action_names_and_types(self.node)
        return print_listing(call, pairs, a, "count_actions")

    @runs("topic type", "service type")
    def _type(self, call: Call, a: dict):
        if a["command"] == "topic":
            pairs, name = self.graph.topics(a.get("include_hidden_topics")), a["topic_name"]
        else:
            pairs, name = self.graph.services(a.get("include_hidden_services")), a["service_name"]
        for n, types in pairs:
            if n == name:
                call.out("".join(f"{t}\n" for t in types))
                return 0
        return 1

    @runs("topic info")
    def _topic_info(self, call: Call, a: dict):
        name = a["topic_name"]
        types = dict(self.graph.topics(True)).get(name)
        if types is None:
            return f"Unknown topic '{name}'"
        end = "\n\n" if a.get("verbose") else "\n"
        shown = types[0] if len(types) == 1 else types
        text = f"Type: {shown}{end}Publisher count: {self.node.count_publishers(name)}{end}"
        if a.get("verbose"):
            text += "".join(f"{i}{end}" for i in self.node.get_publishers_info_by_topic(name))
        text += f"Subscription count: {self.node.count_subscribers(name)}{end}"
        if a.get("verbose"):
            text += "".join(f"{i}{end}" for i in self.node.get_subscriptions_info_by_topic(name))
        call.out(text)
        return 0

    @runs("action info")
    def _action_info(self, call: Call, a: dict):
        name, lines = a["action_name"], [f"Action: {a['action_name']}"]
        for title, of_node in (("clients", get_action_client_names_and_types_by_node),
                               ("servers", get_action_server_names_and_types_by_node)):  # fmt: skip
            found = []
            for n, ns in self.node.get_node_names_and_namespaces():
                for action, types in of_node(self.node, n, ns):
                    if action == name:
                        found.append((full_name(ns, n), ", ".join(types)))
            lines.append(f"Action {title}: {len(found)}")
            if not a.get("count"):
                lines += [f"    {n} [{t}]" if a.get("show_types") else f"    {n}" for n, t in found]
        call.out("\n".join(lines) + "\n")
        return 0

    @runs("node list")
    def _node_list(self, call: Call, a: dict):
        nodes = self.graph.nodes(a.get("all"))
        if a.get("count_nodes"):
            call.out(f"{len(nodes)}\n")
        elif nodes:
            call.out("\n".join(nodes) + "\n")
        return 0

    @runs("node info")
    def _node_info(self, call: Call, a: dict):
        target = a["node_name"]
        if target not in self.graph.nodes(True):
            return f"Unable to find node '{target}'"
        info = node_sections(self.node, target, a.get("include_hidden"))
        call.out(node_info_text(target, info))
        return 0

    # -- interfaces (astiop's definitions: the ones it can show) -----------------------------
    @runs("interface show")
    def _interface_show(self, call: Call, a: dict):
        t = a["type"]
        if t not in DEFINITIONS:
            if t.count("/") != 2:
                return f"Invalid name '{t}'. Expected three parts separated by '/'"
            return f"Unknown interface '{t}'"
        call.out(interface_show(t, self.distro))
        return 0

    @runs("interface list")
    def _interface_list(self, call: Call, a: dict):
        flags = {k for k in INTERFACE_FLAGS if a.get(k)}
        call.out(interface_list_text(list(DEFINITIONS), flags)[0])
        return 0

    # -- parameters, through each node's parameter services ----------------------------------
    @runs("param list")
    def _param_list(self, call: Call, a: dict):
        nodes = self.graph.nodes(a.get("include_hidden_nodes"))
        named = a.get("node_name")
        if named and named not in nodes:
            return "Node not found"
        served = {n for n, _ in self.graph.services(True)}
        asked = [n for n in ([named] if named else nodes) if f"{n}/list_parameters" in served]
        read = read_params(self.ros, asked, 5.0)
        params = [(*key.split(" ", 1), type_) for key, type_ in read]
        flags = {"param_type"} if a.get("param_type") else set()
        options = {"filter": a.get("filter"), "param_prefixes": a.get("param_prefixes")}
        call.out(param_list_text(params, named, flags, options)[0])
        return 0

    def _param_call(self, a: dict, service: str, srv: Any, request: Any) -> Any:
        if a["node_name"] not in self.graph.nodes(a.get("include_hidden_nodes")):
            raise RuntimeError("Node not found")
        try:
            return self.ros.call(srv, f"{a['node_name']}/{service}", request, 10.0)
        except TimeoutError as exc:
            raise RuntimeError(str(exc)) from None

    @runs("param get")
    def _param_get(self, call: Call, a: dict):
        from rcl_interfaces.srv import GetParameters

        request = GetParameters.Request(names=[a["parameter_name"]])
        response = self._param_call(a, "get_parameters", GetParameters, request)
        if not response.values:
            return "Parameter not set"
        pvalue = response.values[0]
        if pvalue.type == 0:
            call.out("Parameter not set.\n")
            return 0
        if pvalue.type not in PARAM_LABELS:
            return f"Unknown parameter type '{pvalue.type}'"
        label, attr = PARAM_LABELS[pvalue.type]
        value = getattr(pvalue, attr)
        if hasattr(value, "tolist"):
            value = value.tolist()
        call.out(f"{value}\n" if a.get("hide_type") else f"{label} {value}\n")
        return 0

    @runs("param set")
    def _param_set(self, call: Call, a: dict):
        from rcl_interfaces.msg import Parameter
        from rcl_interfaces.srv import SetParameters

        parameter = Parameter(name=a["parameter_name"], value=parameter_value(a["value"]))
        request = SetParameters.Request(parameters=[parameter])
        result = self._param_call(a, "set_parameters", SetParameters, request).results[0]
        reason = f": {result.reason}" if result.reason else ""
        if result.successful:
            call.out(f"Set parameter successful{reason}\n")
        else:  # on stderr, and the exit status stays 0 (ros2param/verb/set.py)
            call.err(f"Setting parameter failed{reason}\n")
        return 0

    # -- the daemon: this server (ros2cli/verb/daemon/{start,status,stop}.py) -----------------
    @runs("daemon start")
    def _daemon_start(self, call: Call, a: dict):
        started, self.daemon_running = not self.daemon_running, True
        call.out("The daemon has been started\n" if started else "The daemon is already running\n")
        return 0

    @runs("daemon status")
    def _daemon_status(self, call: Call, a: dict):
        call.out(
            "The daemon is running\n" if self.daemon_running else "The daemon is not running\n"
        )
        return 0

    @runs("daemon stop")
    def _daemon_stop(self, call: Call, a: dict):
        stopped, self.daemon_running = self.daemon_running, False
        call.out("The daemon has been stopped\n" if stopped else "The daemon is not running\n")
        return 0


DdsRos2.VERBS = served((DdsRos2, DdsTopics, DdsCalls))


def parameter_value(text: str) -> Any:
    """ros2param/api get_parameter_value: the YAML value's type, else a string."""
    from rcl_interfaces.msg import ParameterValue

    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        value = text
    kinds: tuple[tuple[type, int], ...] = ((bool, 1), (int, 2), (float, 3))
    for py, kind in kinds:
        if isinstance(value, py):
            return ParameterValue(type=kind, **{PARAM_FIELDS[kind]: value})
    if isinstance(value, list) and value:
        for py, kind in (*kinds, (str, 4)):
            if all(type(v) is py for v in value):
                field = PARAM_LABELS[kind + 5][1]
                return ParameterValue(type=kind + 5, **{field: value})
    return ParameterValue(type=4, string_value=text)
