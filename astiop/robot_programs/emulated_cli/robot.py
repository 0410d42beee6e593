"""The emulated robot: the simulator at real time in its own process, behind a Unix socket.

Each emulated `ros2` call connects, sends its parsed arguments, and gets back what the real
CLI prints, streamed: `topic echo` until SIGINT, `topic hz` every second, `action send_goal`
blocking until the goal ends (SIGINT cancels it), a call to a service nobody serves waiting.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import socket
import sys
import threading
import uuid
from pathlib import Path

import yaml

from astiop.robot_programs.emulated_cli.call import Call, Interrupted
from astiop.robot_programs.emulated_cli.topics import HIDDEN_TOPICS, RobotTopics, listing
from astiop.robot_programs.emulated_cli.verb_table import VerbTable, runs
from astiop.robot_programs.emulated_cli.verbs import run_verb
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.definitions import DEFINITIONS
from astiop.ros2.interfaces import InterfaceError, fill, interface_show, python_repr
from astiop.ros2.printing import (
    INTERFACE_FLAGS,
    indent_yaml,
    interface_list_text,
    param_list_text,
    type_of,
)
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.param_get import WORDS
from astiop.sim.simulator import GoalError, Simulator
from astiop.store import LocationError, Store
from astiop.transports.simulator.backend import SimBackend
from astiop.transports.state import yaw_of

MAP_TYPE = "nav_msgs/msg/OccupancyGrid"


class EmulatedRobot:
    """The simulated robot behind the emulated `ros2`: the service, action, node, interface,
    param and daemon verbs itself, the topic verbs by `RobotTopics`, any other verb as astiop
    runs it in process (verbs.py)."""

    def __init__(
        self,
        folder: Path,
        *,
        seed: int,
        distro: str,
        missing: tuple[str, ...] = (),
        speed: float = 1.0,
        daemon_running: bool = True,
    ):
        self.folder = folder
        self.daemon_running = daemon_running  # the ros2 daemon: up unless the computer just booted
        self.distro = distro
        self.missing = set(missing)
        self.sim = Simulator(seed=seed)
        self.store = Store(folder / "robot.db")  # the robot's own named locations
        self.backend = SimBackend(self.sim, self.store, realtime=True, speed=speed)
        self.catalog = astibot_catalog()
        for node in self.catalog.nodes:  # every ROS 2 node declares it
            self.backend.params.setdefault((node, "use_sim_time"), False)
        self.topic_verbs = RobotTopics(self.backend, self.catalog, self.topics)
        self.verbs = VerbTable(self, self.topic_verbs)

    # -- the graph ---------------------------------------------------------------------------
    def topics(self) -> dict[str, str]:
        names = {n: t.type for n, t in self.catalog.topics.items()}
        names["/map"] = MAP_TYPE
        names.update(HIDDEN_TOPICS)
        return {n: t for n, t in sorted(names.items()) if n not in self.missing}

    def services(self) -> dict[str, str]:
        return {
            n: s.type for n, s in sorted(self.catalog.services.items()) if n not in self.missing
        }

    def actions(self) -> dict[str, str]:
        return {n: a.type for n, a in sorted(self.catalog.actions.items()) if n not in self.missing}

    # -- serving ----------------------------------------------------------------------------
    def serve(self, path: str) -> None:
        self.backend.start()
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
            self.backend.close()

    def _handle(self, conn: socket.socket) -> None:
        call = Call(conn)
        req = call.request
        if req.get("op") == "cmd_vel_log":  # for measurements: when each Twist arrived
            call.out(json.dumps(list(self.topic_verbs.cmd_vel_log)))
            call.finish(0)
            return
        args = req.get("args", {})
        handler = self.verbs.handler((args.get("command"), args.get("verb")))
        if handler is None and (args.get("command"), args.get("verb")) in VERBS:
            handler = functools.partial(self._verb, argv=req.get("argv", []))
        if (args.get("command"), args.get("verb")) in SPAWN_DAEMON and not args.get("no_daemon"):
            self.daemon_running = True
        code = 1
        try:
            if handler is None:
                call.err(f"the emulated robot does not implement ros2 {args.get('command')}\n")
            else:
                code = handler(call, args) or 0
        except Interrupted:
            code = 2  # ros2cli returns signal.SIGINT on KeyboardInterrupt
        except Exception as exc:  # noqa: BLE001 - the robot never dies of one call
            with contextlib.suppress(Interrupted):
                call.err(f"{type(exc).__name__}: {exc}\n")
        call.finish(code)

    def _verb(self, call: Call, a: dict, argv: list[str]) -> int:
        return run_verb(self, call, argv)

    # -- service ----------------------------------------------------------------------------
    @runs("service list")
    def _service_list(self, call: Call, a: dict) -> int:
        return listing(call, self.services(), a.get("show_types"), a.get("count_services"))

    @runs("service type")
    def _service_type(self, call: Call, a: dict) -> int:
        t = self.services().get(a["service_name"])
        if t is None:
            call.err("Unable to find service '{}'\n".format(a["service_name"]))
            return 1
        call.out(t + "\n")
        return 0

    @runs("service call")
    def _service_call(self, call: Call, a: dict) -> int:
        name, type_ = a["service_name"], a["service_type"]
        if type_ not in DEFINITIONS:
            call.err("The passed service type is invalid\n")
            return 1
        text = a.get("stdin_values") if a.get("stdin") else a.get("values", "{}")
        try:
            request = fill(type_, yaml.safe_load(text or "") or {}, part=0)
        except (InterfaceError, yaml.YAMLError) as exc:
            call.err(f"Failed to populate field: {exc}\n")
            return 1
        served = self.services()
        if name not in served or served[name] != type_:
            call.out("waiting for service to become available...\n")
            call.wait(1e9)
        call.out(f"requester: making request: {python_repr(type_, request, 0)}\n\n")
        try:
            response = self.backend.serve(name, request)
        except (GoalError, LocationError) as exc:
            response = {"success": False, "message": str(exc)}
        call.out(f"response:\n{python_repr(type_, response, 1)}\n\n")
        return 0

    # -- action -----------------------------------------------------------------------------
    @runs("action list")
    def _action_list(self, call: Call, a: dict) -> int:
        return listing(call, self.actions(), a.get("show_types"), a.get("count_actions"))

    @runs("action info")
    def _action_info(self, call: Call, a: dict) -> int:
        name = a["action_name"]
        if name not in self.actions():
            call.out(f"Action: {name}\nAction clients: 0\nAction servers: 0\n")
            return 0
        node = self.catalog.actions[name].node
        call.out(f"Action: {name}\nAction clients: 0\nAction servers: 1\n    {node}\n")
        return 0

    @runs("action send_goal")
    def _action_send_goal(self, call: Call, a: dict) -> int:
        name, type_ = a["action_name"], a["action_type"]
        text = a.get("stdin_values") if a.get("stdin") else a.get("goal", "{}")
        if type_ not in DEFINITIONS:
            call.err("The passed action type is invalid\n")
            return 1
        try:
            goal_msg = fill(type_, yaml.safe_load(text or "") or {}, part=0)
        except (InterfaceError, yaml.YAMLError) as exc:
            call.out(f"Failed to populate message fields: {exc!r}\n")
            return 1
        call.out("Waiting for an action server to become available...\n")
        if name not in self.actions():
            call.wait(1e9)
        call.out(f"Sending goal:\n{indent_yaml(goal_msg, 5)}")
        pose = goal_msg["pose"]["pose"]
        try:
            goal = self.sim.goto(
                pose["position"]["x"], pose["position"]["y"], yaw_of(pose["orientation"])
            )
        except GoalError:
            call.out("Goal was rejected.\n")
            return 0
        call.out(f"Goal accepted with ID: {uuid.UUID(int=goal.id).hex}\n\n")
        start = self.sim.t
        try:
            while self.sim.goal is not None and self.sim.goal.id == goal.id:
                call.wait(1.0)
                if a.get("feedback") and self.sim.goal is not None:
                    s = self.sim.snapshot()
                    call.out(
                        "Feedback:\n    "
                        f"distance_remaining: {s.distance_remaining:.3f}\n"
                        f"navigation_time: {self.sim.t - start:.1f}\n\n"
                    )
        except Interrupted:  # the client's finally: cancel the goal it sent
            if self.sim.goal is not None and self.sim.goal.id == goal.id:
                self.sim.cancel("canceled by the action client")  # a cancel, not a latched /stop
            with contextlib.suppress(Interrupted):
                call.out("Canceling goal...\nGoal canceled.\n")
            raise
        result = self.sim.last_result
        ok = result is not None and result.id == goal.id and result.status == "succeeded"
        canceled = result is not None and result.status == "canceled"
        status = "SUCCEEDED" if ok else "CANCELED" if canceled else "ABORTED"
        # message_to_yaml of the result, as send_goal.py prints it (Humble: an Empty `result`)
        fields = {"result": {}} if self.distro == "humble" else {"error_code": 0, "error_msg": ""}
        if not ok and "error_code" in fields:
            fields = {"error_code": 1, "error_msg": result.message if result else "aborted"}
        body = yaml.safe_dump(fields, sort_keys=False, default_flow_style=False)
        call.out(f"Result:\n    {body}\nGoal finished with status: {status}\n")
        return 0

    # -- node, interface, param, daemon ------------------------------------------------------
    @runs("node list")
    def _node_list(self, call: Call, a: dict) -> int:
        nodes = sorted(self.catalog.nodes)
        if a.get("count_nodes"):
            call.out(f"{len(nodes)}\n")
        else:
            call.out("\n".join(nodes) + "\n")
        return 0

    @runs("node info")
    def _node_info(self, call: Call, a: dict) -> int:
        name = a["node_name"]
        if name not in self.catalog.nodes:
            call.err(f"Unable to find node '{name}'\n")
            return 1
        lines = [name]
        for section, items in self.catalog.node_info(name).items():
            lines.append(f"  {section}:")
            lines += [f"    {n}: {t}" for n, t in items if n not in self.missing]
        call.out("\n".join(lines) + "\n")
        return 0

    @runs("interface show")
    def _interface_show(self, call: Call, a: dict) -> int:
        t = a["type"]
        if t not in DEFINITIONS:
            call.err(
                f"Unknown interface '{t}'\n"
                if t.count("/") == 2
                else f"Invalid name '{t}'. Expected three parts separated by '/'\n"
            )
            return 1
        call.out(interface_show(t))
        return 0

    @runs("interface list")
    def _interface_list(self, call: Call, a: dict) -> int:
        call.out(
            interface_list_text(list(DEFINITIONS), {k for k in INTERFACE_FLAGS if a.get(k)})[0]
        )
        return 0

    @runs("param list")
    def _param_list(self, call: Call, a: dict) -> int:
        node_name = a.get("node_name")
        if node_name and node_name not in self.catalog.nodes:
            call.out("Node not found\n")  # ros2param/verb/list.py
            return 0
        params = [(n, p, type_of(v)) for (n, p), v in self.backend.params.items()]
        flags = {"param_type"} if a.get("param_type") else set()
        options = {"filter": a.get("filter"), "param_prefixes": a.get("param_prefixes")}
        call.out(param_list_text(params, node_name, flags, options)[0])
        return 0

    @runs("param get")
    def _param_get(self, call: Call, a: dict) -> int:
        key = (a["node_name"], a["parameter_name"])
        if a["node_name"] not in self.catalog.nodes:
            call.err("Node not found\n")
            return 1
        if key not in self.backend.params:
            call.out("Parameter not set.\n")
            return 0
        value = self.backend.params[key]
        call.out(f"{WORDS[type(value)]} value is: {value}\n")
        return 0

    @runs("param set")
    def _param_set(self, call: Call, a: dict) -> int:
        key = (a["node_name"], a["parameter_name"])
        if a["node_name"] not in self.catalog.nodes:
            call.err("Node not found\n")
            return 1
        value = yaml.safe_load(a["value"])
        current = self.backend.params.get(key)
        if current is None or type(value) is not type(current):
            # rclcpp refuses a type change and says so on stdout; the exit status stays 0
            call.out(
                f"Setting parameter failed: Wrong parameter type, parameter {{{key[1]}}} is of type "
                f"{{{type(current).__name__}}}, setting it to {{{type(value).__name__}}} is not allowed.\n"
            )
            return 0
        self.backend.params[key] = value
        call.out("Set parameter successful\n")
        return 0

    # The messages of ros2cli/verb/daemon/{start,status,stop}.py, humble and jazzy alike.
    @runs("daemon start")
    def _daemon_start(self, call: Call, a: dict) -> int:
        started, self.daemon_running = not self.daemon_running, True
        call.out("The daemon has been started\n" if started else "The daemon is already running\n")
        return 0

    @runs("daemon status")
    def _daemon_status(self, call: Call, a: dict) -> int:
        call.out(
            "The daemon is running\n" if self.daemon_running else "The daemon is not running\n"
        )
        return 0

    @runs("daemon stop")
    def _daemon_stop(self, call: Call, a: dict) -> int:
        stopped, self.daemon_running = self.daemon_running, False
        call.out("The daemon has been stopped\n" if stopped else "The daemon is not running\n")
        return 0


# The verbs that build a NodeStrategy, which spawns the daemon when it is down
# (ros2cli/node/strategy.py; each */verb/*.py, humble and jazzy). pub, hz, service call,
# send_goal and interface use a DirectNode or none and leave the daemon as it is.
SPAWN_DAEMON = {
    *(("topic", v) for v in ("echo", "find", "info", "list", "type")),
    *(("service", v) for v in ("echo", "find", "info", "list", "type")),
    *(("action", v) for v in ("info", "list", "type")),
    *(("node", v) for v in ("info", "list")),
    *(("param", v) for v in ("delete", "describe", "dump", "get", "list", "load", "set")),
}

CLIENT = """#!{python}
# The emulated ros2 of `astiop emulate-ros2` ({distro}); written by astiop.
import sys
from astiop.robot_programs.emulated_cli.client import main
sys.exit(main(sys.argv[1:], {folder!r}))
"""


def write_client(folder: Path, *, distro: str, latency_ms: int, missing: tuple[str, ...]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    info = {
        "socket": str(folder / "robot.sock"),
        "distro": distro,
        "latency_ms": latency_ms,
        "missing": list(missing),
        "pid": os.getpid(),
    }
    (folder / "robot.json").write_text(json.dumps(info), encoding="utf-8")
    exe = folder / "ros2"
    exe.write_text(
        CLIENT.format(python=sys.executable, distro=distro, folder=str(folder)), encoding="utf-8"
    )
    exe.chmod(0o755)
    return exe
