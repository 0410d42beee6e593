"""The real robot: the same checked commands, run by the `ros2` executable (never a shell).

Live state comes from long-lived `ros2 topic echo` streams; long-running verbs run under
`Popen` and are stopped with SIGINT so the real client cancels what it started.
"""

from __future__ import annotations

import re
import shutil
import threading
import time
from typing import Any

from astiop.ros2.grammar import current_distro
from astiop.ros2.interfaces import decode_bytes
from astiop.ros2.printing import echo_text
from astiop.ros2.profile import ProfileSpec
from astiop.ros2.render import STAMPED, flow_yaml, sent_argv
from astiop.ros2.transforms import STALE_S, TransformTable
from astiop.ros2.validation import CANCEL_SUFFIX, Checked
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import CALL, GOAL, SAMPLE, TAKE
from astiop.transports import live_robot
from astiop.transports.base import BackendError, RobotBackend
from astiop.transports.event_log import Contact, EstopWork, EventLog
from astiop.transports.inflight import ENDED, InFlight, Job
from astiop.transports.live_catalog import (
    CANCEL_GOAL,
    RELEASE,
    navigation_actions,
    nothing_listed,
    stop_service_type,
)
from astiop.transports.live_robot import without_finished_plan
from astiop.transports.ros2cli import process as ros2_process
from astiop.transports.ros2cli.estop_probe import StopProbe
from astiop.transports.ros2cli.graph import GraphReader
from astiop.transports.ros2cli.motion import (
    ESTOP_BURST,
    STDIN_DISTROS,
    ArmedStop,
    TeleopPublisher,
    zero_message,
)
from astiop.transports.ros2cli.replies import (
    FAILED_WITH_STATUS_0,
    parse_response,
    without_display_options,
)
from astiop.transports.ros2cli.streams import TopicStream, parse_document
from astiop.transports.state import (
    GOAL_STATUS,
    OccupancyGrid,
    RobotEvent,
    RobotState,
    TopicStat,
    from_messages,
    goal_status_topic,
    grid_from_message,
    live_topic_stats,
)

ARRAYS = {"/scan", "/plan", "/obstacles"}  # echoed in full: ros2 truncates at 128 items
GRAPH_REFRESH_S = 30.0
ZERO_PUB_S = 1.0  # an E-STOP's ten zero Twists at 10 Hz: a second on top of the start-up
DISCOVERY_YOUNG_S = 10.0  # a process this young may not have the whole robot in its lists
NO_GOAL_AFTER_S = 5.0  # a latched goal status echoed this long and none came: no goal yet


def _waited_for_service(out: str) -> bool:
    """`ros2 service call` found no server of its type (ros2service/verb/call.py waits)."""
    return "waiting for service" in out and "response:" not in out


def _unsent(out: str) -> bool:
    """A `ros2 service call` still waiting for its server: it sent no request yet."""
    return "requester:" not in out


def _zero_burst(name: str, type_: str) -> list[str]:
    """`ros2 topic pub` of the E-STOP's zero Twists."""
    return ["topic", "pub", *ESTOP_BURST, name, type_, flow_yaml(zero_message(type_))]


class Ros2Backend(RobotBackend):
    name = "ros2"
    capabilities = frozenset({"commands", "teleop"})

    def __init__(
        self,
        executable: str = "ros2",
        timeout_s: float = 10.0,
        *,
        stream: bool = True,
        discover: bool = True,
        fixed: ProfileSpec | None = None,
    ):
        """`discover=False` (an E-STOP from a new process): the graph is not read first (a
        `daemon start`, then up to three rounds of five list calls: 10-25 s with the real CLI)."""
        path = shutil.which(executable)
        if path is None:
            raise BackendError(
                f"'{executable}' was not found on PATH: source your ROS 2 setup "
                "(e.g. /opt/ros/jazzy/setup.bash) or use --robot sim"
            )
        self.executable = path
        self.timeout_s = timeout_s
        self.distro = current_distro()
        self.stream = stream
        self.inflight = InFlight()
        self._teleop_job: Job | None = None  # while teleop holds a velocity
        self._lock = threading.Lock()
        self._latest: dict[str, dict[str, Any]] = {}
        self._received: dict[str, float] = {}  # on the robot clock: s since t0
        self._streams: dict[str, TopicStream] = {}
        self._goal_stream_at: float | None = None  # when the goal status echo started
        self._transforms: dict[str, TransformTable] = {}  # /tf, /tf_static: fed by one stream each
        self._goal_procs: list[Any] = []
        self._last_outcome: str | None = None
        self._map: OccupancyGrid | None = None
        self._teleop: TeleopPublisher | None = None
        self._armed: ArmedStop | None = None
        self.t0 = time.monotonic()
        self.events = EventLog(self.t0)
        self._estop = EstopWork(self.events)
        self._contact = Contact(self.events, on_return=self._rearm)
        self._closed = threading.Event()
        self._fixed = fixed or ProfileSpec()  # what the operator fixed: a file, a namespace
        self._graph = GraphReader(self._run, timeout_s, self._fixed)
        self.discovered = discover
        self.catalog = self._graph.read() if discover else self._graph.describe(nothing_listed())
        self.refreshed_at = time.monotonic()

    # -- the live graph -----------------------------------------------------------------
    def _name(self, role: str, default: str = "") -> str:
        """The robot's name for `role` (its profile); before the graph is read, `default` under
        the robot's namespace ("" for a role without a conventional name)."""
        name = self.catalog.profile.name(role) if self.catalog.profile else None
        return name or (self._fixed.namespace + default if default else "")

    def _run(self, argv: list[str], timeout: float, **kw) -> ros2_process.Run:
        """`ros2 ARGV`; inside an actuating command's job, the E-STOP kills it."""
        job = self.inflight.current_job()
        return ros2_process.run(self.executable, argv, timeout, job=job, **kw)

    def discovering(self) -> bool:
        # a new process's first lists (the daemon's, or a fresh discovery) may be partial
        return time.monotonic() - self.t0 < DISCOVERY_YOUNG_S

    def refresh(self, settle: bool = True) -> bool:
        """Read the graph again (a name was missing, or 30 s passed); False if it failed.
        Each read is a `ros2` process of its own, settled or not."""
        try:
            self.catalog = self._graph.describe(self._graph.lists())
        except BackendError:
            return False
        self.refreshed_at, self.discovered = time.monotonic(), True
        return True

    def _refresh_loop(self) -> None:
        while not self._closed.wait(GRAPH_REFRESH_S):
            self.refresh()

    # -- lifecycle ------------------------------------------------------------------------
    def start(self) -> None:
        cmd_vel = self.catalog.topics.get(self._name("velocity_command"))
        if cmd_vel is not None:
            self._teleop = TeleopPublisher(
                self.executable, cmd_vel.name, cmd_vel.type, on_lapse=self._teleop_lapsed
            )
            if self.distro in STDIN_DISTROS:
                self._armed = ArmedStop(self.executable, cmd_vel.name, cmd_vel.type)
                if not self.inflight.held:
                    self._armed.arm()
        if not self.stream:
            return
        # odometry only when it is the pose (50 Hz of YAML costs more than it tells)
        names = self.catalog.state_topics()
        odom = self._name("odometry")
        if odom in names and self._name("pose") != odom and self._name("status"):
            names.remove(odom)
        for name in names:
            extra = ("--full-length",) if name in ARRAYS else ()
            spec = self.catalog.topics[name]
            self._streams[name] = TopicStream(
                self.executable, name, spec.type, self._on_message, self.events.add, extra
            ).start()
        goals = goal_status_topic(self.catalog.profile)
        if goals:  # a Nav2 robot's state word: does its action run a goal (a hidden topic)
            self._streams[goals] = TopicStream(
                self.executable, goals, GOAL_STATUS, self._on_message, self.events.add
            ).start()
            self._goal_stream_at = time.monotonic()
        if self._name("map"):
            threading.Thread(target=self._read_map, name="ros2-map", daemon=True).start()
        threading.Thread(target=self._refresh_loop, name="ros2-graph", daemon=True).start()

    def close(self) -> None:
        self._closed.set()
        for s in self._streams.values():
            s.stop()
        self._streams.clear()
        if self._teleop is not None:
            self._teleop.close()
        if self._armed is not None:
            self._armed.disarm()
        for proc in list(self._goal_procs):
            ros2_process.stop(proc, 3.0)  # the client cancels its goal

    # -- live state -----------------------------------------------------------------------
    def _on_message(self, name: str, msg: dict[str, Any], received: float) -> None:
        if name == self._name("status"):
            self.events.status(str(msg.get("state")), str(msg.get("fault") or ""))
        if name in (self._name("transforms"), self._name("static_transforms")):
            static = name == self._name("static_transforms")
            table = self._transforms.setdefault(name, TransformTable(None if static else STALE_S))
            table.fold(msg, received)  # the tree so far, not this message's few transforms
            msg = table.message(received) or msg
        with self._lock:
            self._latest[name] = msg
            self._received[name] = received - self.t0

    def robot_time(self) -> float:
        return time.time()  # ros2 runs on this machine's clock, as the robot's drivers do

    def state(self) -> RobotState:
        with self._lock:
            messages = dict(self._latest)
        seq = self.events.seq
        profile = self.catalog.profile
        goals = goal_status_topic(profile)
        # the status is latched (rcl_action): an echo running this long without one means its
        # server has had no goal; before that (a `ros2` starting up) the state is not known
        since = self._goal_stream_at
        waited = since is not None and time.monotonic() - since > NO_GOAL_AFTER_S
        if goals in self._streams and goals not in messages and waited:
            messages[goals] = {"status_list": []}
        messages = without_finished_plan(messages, profile)
        now = time.monotonic()
        state = from_messages(
            now - self.t0, messages, e_stopped=self.inflight.held, event_seq=seq, profile=profile
        )
        return state.with_lost(self._lost_for(now))

    def _lost_for(self, now: float) -> float | None:
        """Seconds since the robot was last heard, when it is lost (said once, as is its
        return)."""
        return self._contact.check([s.age(now) for s in self._streams.values()])

    def _rearm(self) -> None:
        """The robot is back: the E-STOP's armed publisher may have ended with it."""
        if self._armed is not None and not self.inflight.held:
            self._armed.arm()

    def messages(self, names) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {n: self._latest[n] for n in names if n in self._latest}

    def message_times(self, names) -> dict[str, float]:
        with self._lock:
            return {name: self._received[name] for name in names if name in self._received}

    def events_since(self, seq: int) -> list[RobotEvent]:
        return self.events.since(seq)

    def topic_stats(self) -> list[TopicStat]:
        return live_topic_stats(self.catalog.topics, self._streams, time.monotonic())

    def map_geometry(self):
        return self._map

    def read_map(self, timeout_s: float):
        if self._map is None and self._name("map") in self.catalog.topics:
            self._read_map()
        return self._map

    def _read_map(self) -> None:
        name = self._name("map")
        spec = self.catalog.topics[name]
        argv = ["topic", "echo", name, spec.type, "--once", "--full-length"]
        argv += ["--qos-durability", "transient_local", "--qos-reliability", "reliable"]
        run = self._run(argv, 30.0)
        doc = parse_document(run.out.split("\n---", 1)[0].splitlines(keepends=True))
        if doc is None:
            self.events.add("map", "warning", f"no {name} received: the map view follows the scan")
            return
        try:
            self._map = grid_from_message(doc)
        except (KeyError, TypeError, ValueError) as exc:
            self.events.add("map", "warning", f"{name} could not be read: {exc}")

    def wait_until_idle(self, timeout_s: float) -> str | None:
        def state() -> str | None:
            with self._lock:
                return (self._latest.get(self._name("status")) or {}).get("state")

        # a goal's client is followed until its last line is read (its outcome), not only
        # until its process exits: the follower drops it from the list then
        return live_robot.wait_until_idle(
            timeout_s,
            lost=lambda: self._lost_for(time.monotonic()) is not None,
            goals_running=lambda: bool(self._goal_procs),
            state=state,
            outcome=lambda: self._last_outcome,
        )

    # -- E-STOP and teleop -----------------------------------------------------------------
    @property
    def e_stopped(self) -> bool:
        return self.inflight.held

    def estop(self) -> list[str]:
        """Everything in flight ended first (a timed publish's process killed, goals' clients
        stopped so they cancel, teleop halted), then the zero Twist (armed, or spawned) and /stop
        in parallel; no step waits for another. Failures after this returns arrive as events."""
        failures = self.inflight.stop_all()
        if self._teleop is not None:
            self._teleop.halt()
        self._estop.begin()
        cmd_vel = self.catalog.topics.get(self._name("velocity_command"))
        fired = self._armed.fire() if self._armed is not None else None
        if fired is not None:
            self._estop.start(lambda: self._reap(fired, "zero velocity"), "estop zero velocity")
        elif cmd_vel is not None:
            burst = _zero_burst(cmd_vel.name, cmd_vel.type)
            self._background(lambda: burst, "zero velocity", ZERO_PUB_S)
        elif not self.discovered:  # its type asked of the robot first, in the same thread
            self._background(self._typed_zero_burst, "zero velocity", ZERO_PUB_S)
        else:
            failures.append("the robot has no velocity command: no zero Twist was sent")
        stop = self._name("stop") if self.discovered else self._fixed.namespace + "/stop"
        if stop:
            stop_type = stop_service_type(self.catalog)  # not read yet: the catalog's type
            answered = threading.Event()
            probe = None if self.discovered else self._stop_probe(answered)
            absent = probe.stop_absent if probe else None
            argv = ["service", "call", stop, stop_type, "{}"]
            self._background(lambda: argv, stop, absent=absent, finished=answered)
            if probe is not None:  # a robot with no /stop: its Nav2 goals cancelled instead
                self._estop.start(probe.probe, "estop probe")
        if not stop:
            # no stop service (a TurtleBot3 under Nav2): every navigation goal on the robot
            # cancelled, another client's too (action_msgs/srv/CancelGoal: a zero id and stamp
            # cancel all, ros2/rcl_interfaces humble and jazzy)
            actions = navigation_actions(self.catalog, self._fixed.namespace)
            for action in actions:
                call = ["service", "call", f"{action}{CANCEL_SUFFIX}", CANCEL_GOAL, "{}"]
                self._background(lambda call=call: call, f"cancel every {action} goal")
            if actions:  # how such a robot stops: said, not failed (as through rclpy)
                self.events.add(
                    "estop",
                    "info",
                    f"the robot has no stop service ({self._fixed.namespace}/stop): "
                    f"every goal of {', '.join(actions)} is being cancelled instead",
                )
            else:
                failures.append("the robot has neither a stop service nor a navigation action")
        self._estop.said(failures)
        return failures

    def settle_estop(self, timeout_s: float) -> list[str]:
        """The zero Twist's `ros2 topic pub` and the `/stop` call run to their end (a real `ros2`
        takes 0.7-3 s to start): an `astiop estop` must not say it stopped the robot before."""
        lookup_s = 0.0 if self.discovered else self.timeout_s  # `ros2 topic type` first
        return self._estop.settle(lookup_s + timeout_s + ZERO_PUB_S)

    def _typed_zero_burst(self) -> list[str]:
        """The zero burst in /cmd_vel's type as the robot's graph has it (ros2topic's `topic
        type` prints it: ros2topic/verb/type.py, humble and jazzy). Asked again until found: a
        daemon it had to start has discovered nothing yet (its first answer spins 0.5 s on its
        own: ros2cli/node/direct.py), and the next call asks that daemon."""
        deadline = time.monotonic() + self.timeout_s
        while True:
            left = deadline - time.monotonic()
            name = self._fixed.namespace + "/cmd_vel"
            run = self._run(["topic", "type", name], max(left, 0.1))
            types = run.out.split() if run.returncode == 0 else []
            if types:  # a TwistStamped base's, when a Twist is listed too (as describe_graph)
                return _zero_burst(name, STAMPED if STAMPED in types else types[0])
            if run.stopped or time.monotonic() + 0.1 >= deadline:
                # stderr is no failure by itself (rcl warns there), but it may say why
                said = f" ({run.err.strip()[-200:]})" if run.err.strip() else ""
                raise BackendError(
                    f"no /cmd_vel on the robot's graph in {self.timeout_s:g} s{said}: "
                    "no zero Twist was sent"
                )
            time.sleep(0.1)

    def _stop_probe(self, answered: threading.Event) -> StopProbe:
        return StopProbe(
            self._run,
            self._fixed.namespace,
            self.timeout_s,
            lambda argv, what: self._background(lambda: argv, what),
            answered,
        )

    def _background(
        self,
        argv_of,
        what: str,
        extra_s: float = 0.0,
        absent: threading.Event | None = None,
        finished: threading.Event | None = None,
    ) -> None:
        """`ros2 ARGV` in a thread of the E-STOP's; `argv_of()` may itself ask the robot. Set,
        `absent` ends the call: what it waits for is not on the robot (said elsewhere);
        `finished` is set when it ends."""

        def go() -> None:
            try:
                # ended as absent only while it still waits for its server: a request already
                # sent (a slow but real /stop) runs to its answer
                run = self._run(
                    argv_of(), self.timeout_s + extra_s, cancel=absent, cancellable=_unsent
                )
            except BackendError as exc:
                self.events.add("estop", "error", f"E-STOP {what}: {exc}")
                return
            finally:
                if finished is not None:
                    finished.set()
            if absent is not None and absent.is_set() and run.stopped and _unsent(run.out):
                self.events.add("estop", "info", f"E-STOP: the robot serves no {what}")
                return
            if run.returncode != 0 or run.stopped:
                why = run.err.strip()[-200:] or ("timed out" if run.stopped else "failed")
                if _waited_for_service(run.out):
                    why = f"nothing answered it in {self.timeout_s + extra_s:g} s"
                self.events.add("estop", "error", f"E-STOP {what}: {why}")

        self._estop.start(go, f"estop {what}")

    def _reap(self, proc, what: str) -> None:
        try:
            rc = proc.wait(self.timeout_s)
        except Exception:  # noqa: BLE001
            ros2_process.stop(proc, 1.0)
            rc = None
        if rc != 0:
            err = (proc.stderr.read() or "").strip()[-200:] if proc.stderr else ""
            self.events.add("estop", "error", f"E-STOP {what}: {err or f'exit status {rc}'}")

    def release_estop(self, *, robot: bool = True) -> list[str]:
        self.inflight.release()
        if self._armed is not None:
            self._armed.arm()
        name = self._name("release", RELEASE)  # under the robot's namespace
        spec = self.catalog.services.get(name)
        if spec is None or not robot:
            return []
        # a robot that latches its own stop lets go too
        run = self._run(["service", "call", name, spec.type, "{}"], self.timeout_s)
        if run.returncode == 0 and not run.stopped and not _waited_for_service(run.out):
            return []
        why = f"release {name}: " + (run.err.strip()[-200:] or f"no answer in {self.timeout_s:g} s")
        self.events.add("estop", "error", why)
        return [why]

    def drive(self, twist: dict) -> None:
        if self._teleop is None:
            raise BackendError("the robot has no /cmd_vel")
        job = self._teleop_held()
        with job.sending():
            self._teleop.drive(twist)
        if self._teleop_job is not job:  # it lapsed meanwhile: this key's publisher is new
            self._teleop_held()

    def _teleop_held(self) -> Job:
        with self._lock:
            if self._teleop_job is None:  # refused while the E-STOP holds
                self._teleop_job = self.inflight.start("teleop", self._halt_teleop)
            return self._teleop_job

    def _halt_teleop(self) -> None:
        with self._lock:
            self._teleop_job = None
        if self._teleop is not None:
            self._teleop.halt()

    def _teleop_lapsed(self) -> None:
        """Teleop's keys stopped and its publisher was stopped: nothing of it is in flight."""
        with self._lock:
            job, self._teleop_job = self._teleop_job, None
        if job is not None:
            job.done()

    # -- commands -------------------------------------------------------------------------
    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        with self.actuating(checked) as job:  # refused while the E-STOP holds, ended by it
            try:
                return self._execute(checked, timeout)
            except BackendError:
                if job is not None and job.ended_by_estop:
                    raise BackendError(f"{ENDED}: its ros2 process was killed") from None
                raise

    def _execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        verb = VERBS[checked.command.key]
        means = {TAKE: self._echo, SAMPLE: self._sample, GOAL: self._send_goal}
        return means.get(verb.means, self._once)(checked, sent_argv(checked), timeout)

    def _once(self, checked: Checked, argv: list[str], timeout: float) -> tuple[str, Any]:
        """A verb ros2 ends by itself: a query, a publish, a service call."""
        cmd = checked.command
        if cmd.key == ("topic", "pub") and "times" in cmd.options:
            # never stop a publisher that validation allowed to run this long
            rate = cmd.options.get("rate", 1.0)
            timeout = max(timeout, (cmd.options["times"] - 1) / rate + timeout)
        run = self._run(argv, timeout)
        calls = VERBS[cmd.key].means == CALL
        if calls and _waited_for_service(run.out):
            raise BackendError(f"service {cmd.name} is not available (waited {timeout:g} s)")
        if run.stopped:
            raise BackendError(f"ros2 {' '.join(argv[:3])} timed out after {timeout:g} s")
        if run.returncode != 0:
            raise BackendError(f"ros2 exited with {run.returncode}: {run.err.strip()[:300]}")
        failed = FAILED_WITH_STATUS_0.search(run.out)
        if failed:  # rclcpp refuses on stdout and ros2 still exits 0: it did not happen
            raise BackendError(failed[0].strip()[:300])
        if calls:
            values = parse_response(run.out)
            if checked.local_name == "/stop":
                self.cancel_goals()
            return run.out, values
        return run.out, None

    def _echo(self, checked: Checked, argv: list[str], timeout: float):
        # the robot is asked for whole values; the operator's display options (-l, --no-arr,
        # --no-str) shape only the text, made here from those values by echo_text
        argv = without_display_options(argv)
        if "--once" not in argv:
            argv.append("--once")
        argv.append("--full-length")
        run = self._run(argv, timeout, until=lambda out: "\n---" in out)
        doc = parse_document(run.out.split("\n---", 1)[0].splitlines(keepends=True))
        if doc is None:
            if run.stopped:
                raise BackendError(f"no reading from {checked.command.name} in {timeout:g} s")
            raise BackendError(run.err.strip()[:300] or f"no reading from {checked.command.name}")
        doc = decode_bytes(checked.type, doc)
        return echo_text(doc, checked.command), doc

    def _sample(self, checked: Checked, argv: list[str], timeout: float):
        """A verb ros2 runs until stopped (hz, bw): read until the verb has enough of it."""
        verb = VERBS[checked.command.key]
        run = self._run(argv, timeout, until=verb.enough)
        values = verb.read(run.out)
        if values is None:
            raise BackendError(
                f"{checked.command.name} is not being published (nothing within {timeout:g} s)"
            )
        return run.out, values

    def _send_goal(self, checked: Checked, argv: list[str], timeout: float):
        """Return at acceptance; the client keeps running and is followed to the end."""
        result = ros2_process.Run(argv)  # filled by the follower thread
        # a job of its own for the goal's life: the E-STOP stops its client, which cancels it
        goal = self.inflight.start(f"goal {checked.command.name}", name=checked.command.name)
        try:  # SIGINT, not a kill: its client cancels the goal on the robot
            proc = ros2_process.spawn_owned(self.executable, argv, goal, _stop_in_background)
        except BackendError:
            goal.done()
            raise
        accepted = threading.Event()

        def follow() -> None:
            for line in proc.stdout:
                result.stdout.append(line)
                if "Goal accepted" in line or "Goal was rejected" in line:
                    accepted.set()
                m = re.match(r"Goal finished with status: (\w+)", line)
                if m:
                    self._last_outcome = m[1].lower()
                    self.events.add("goal", "info", f"goal finished: {m[1]}")
                elif line.startswith("Goal canceled."):
                    self._last_outcome = "canceled"
                    self.events.add("goal", "warning", "goal canceled")
            proc.wait()
            goal.done()
            accepted.set()
            if proc in self._goal_procs:
                self._goal_procs.remove(proc)

        self._goal_procs.append(proc)
        self._last_outcome = None
        threading.Thread(target=follow, name="send_goal", daemon=True).start()
        if not accepted.wait(timeout):
            ros2_process.stop(proc, 3.0)
            raise BackendError(f"the action server did not accept the goal within {timeout:g} s")
        out = result.out
        m = re.search(r"Goal accepted with ID: (\w+)", out)
        if m is None:
            return out, {"accepted": False, "status": "REJECTED" if "rejected" in out else None}
        return out, {"accepted": True, "goal_id": m[1], "status": "ACCEPTED"}

    def cancel_goals(self) -> None:
        for proc in list(self._goal_procs):
            _stop_in_background(proc)


def _stop_in_background(proc) -> None:
    """SIGINT a goal's client (it cancels the goal), then harder, without waiting here."""
    threading.Thread(target=ros2_process.stop, args=(proc, 3.0), daemon=True).start()
