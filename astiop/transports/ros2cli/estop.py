"""The `ros2` transport's E-STOP: in-flight work ended, the zero Twists, the /stop call (or its
probe), the goals cancelled, and its release."""

from __future__ import annotations

import subprocess
import threading
import time
from collections.abc import Callable

from astiop.ros2.render import STAMPED, flow_yaml
from astiop.ros2.validation import CANCEL_SUFFIX
from astiop.transports.base import BackendError
from astiop.transports.event_log import EstopWork, EventLog
from astiop.transports.inflight import InFlight
from astiop.transports.live_catalog import (
    CANCEL_GOAL,
    RELEASE,
    LiveGraph,
    navigation_actions,
    stop_service_type,
)
from astiop.transports.ros2cli import process as ros2_process
from astiop.transports.ros2cli.estop_probe import StopProbe
from astiop.transports.ros2cli.motion import ESTOP_BURST, ArmedStop, TeleopPublisher, zero_message
from astiop.transports.ros2cli.process import RunRos2
from astiop.transports.ros2cli.replies import unsent, waited_for_service

ZERO_PUB_S = 1.0  # an E-STOP's ten zero Twists at 10 Hz: a second on top of the start-up


def _zero_burst(name: str, type_: str) -> list[str]:
    """`ros2 topic pub` of the E-STOP's zero Twists."""
    return ["topic", "pub", *ESTOP_BURST, name, type_, flow_yaml(zero_message(type_))]


def _given(argv: list[str]) -> Callable[[], list[str]]:
    """An argv known now, as `CliEstop._background` takes one (each its own, in a loop)."""
    return lambda: argv


class CliEstop:
    """The E-STOP through `run` (`ros2 ARGV`): it owns what it started in the background, and
    the armed zero burst (Kilted and later) it fires; teleop's publisher it halts."""

    def __init__(
        self,
        run: RunRos2,
        live: LiveGraph,
        inflight: InFlight,
        events: EventLog,
        timeout_s: float,
    ):
        self._run = run
        self.live = live
        self.inflight = inflight
        self.events = events
        self.timeout_s = timeout_s
        self.work = EstopWork(events)
        self.teleop: TeleopPublisher | None = None  # teleop's `ros2 topic pub`, once started
        self.armed: ArmedStop | None = None  # a zero burst waiting on stdin, fired at once

    def arm(self, executable: str, topic: str, type_: str) -> None:
        """A zero burst made ready on `topic` now (armed while the E-STOP does not hold)."""
        self.armed = ArmedStop(executable, topic, type_)
        if not self.inflight.held:
            self.armed.arm()

    def rearm(self) -> None:
        """The robot is back: the armed publisher may have ended with it."""
        if self.armed is not None and not self.inflight.held:
            self.armed.arm()

    def close(self) -> None:
        if self.armed is not None:
            self.armed.disarm()

    def estop(self) -> list[str]:
        """Everything in flight ended first (a timed publish's process killed, goals' clients
        stopped so they cancel, teleop halted), then the zero Twist (armed, or spawned) and /stop
        in parallel; no step waits for another. Failures after this returns arrive as events."""
        failures = self.inflight.stop_all()
        if self.teleop is not None:
            self.teleop.halt()
        self.work.begin()
        cmd_vel = self.live.catalog.topics.get(self.live.name("velocity_command"))
        fired = self.armed.fire() if self.armed is not None else None
        if fired is not None:
            self.work.start(lambda: self._reap(fired, "zero velocity"), "estop zero velocity")
        elif cmd_vel is not None:
            burst = _zero_burst(cmd_vel.name, cmd_vel.type)
            self._background(lambda: burst, "zero velocity", ZERO_PUB_S)
        elif not self.live.discovered:  # its type asked of the robot first, in the same thread
            self._background(self._typed_zero_burst, "zero velocity", ZERO_PUB_S)
        else:
            failures.append("the robot has no velocity command: no zero Twist was sent")
        stop = (
            self.live.name("stop") if self.live.discovered else self.live.fixed.namespace + "/stop"
        )
        if stop:
            stop_type = stop_service_type(self.live.catalog)  # not read yet: the catalog's type
            answered = threading.Event()
            probe = None if self.live.discovered else self._stop_probe(answered)
            absent = probe.stop_absent if probe else None
            argv = ["service", "call", stop, stop_type, "{}"]
            self._background(lambda: argv, stop, absent=absent, finished=answered)
            if probe is not None:  # a robot with no /stop: its Nav2 goals cancelled instead
                self.work.start(probe.probe, "estop probe")
        if not stop:
            # no stop service (a TurtleBot3 under Nav2): every navigation goal on the robot
            # cancelled, another client's too (action_msgs/srv/CancelGoal: a zero id and stamp
            # cancel all, ros2/rcl_interfaces humble and jazzy)
            actions = navigation_actions(self.live.catalog, self.live.fixed.namespace)
            for action in actions:
                call = ["service", "call", f"{action}{CANCEL_SUFFIX}", CANCEL_GOAL, "{}"]
                self._background(_given(call), f"cancel every {action} goal")
            if actions:  # how such a robot stops: said, not failed (as through rclpy)
                self.events.add(
                    "estop",
                    "info",
                    f"the robot has no stop service ({self.live.fixed.namespace}/stop): "
                    f"every goal of {', '.join(actions)} is being cancelled instead",
                )
            else:
                failures.append("the robot has neither a stop service nor a navigation action")
        self.work.said(failures)
        return failures

    def settle(self, timeout_s: float) -> list[str]:
        """The zero Twist's `ros2 topic pub` and the `/stop` call run to their end (a real `ros2`
        takes 0.7-3 s to start): an `astiop estop` must not say it stopped the robot before."""
        lookup_s = 0.0 if self.live.discovered else self.timeout_s  # `ros2 topic type` first
        return self.work.settle(lookup_s + timeout_s + ZERO_PUB_S)

    def _typed_zero_burst(self) -> list[str]:
        """The zero burst in /cmd_vel's type as the robot's graph has it (ros2topic's `topic
        type` prints it: ros2topic/verb/type.py, humble and jazzy). Asked again until found: a
        daemon it had to start has discovered nothing yet (its first answer spins 0.5 s on its
        own: ros2cli/node/direct.py), and the next call asks that daemon."""
        deadline = time.monotonic() + self.timeout_s
        while True:
            left = deadline - time.monotonic()
            name = self.live.fixed.namespace + "/cmd_vel"
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
            self.live.fixed.namespace,
            self.timeout_s,
            lambda argv, what: self._background(lambda: argv, what),
            answered,
        )

    def _background(
        self,
        argv_of: Callable[[], list[str]],
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
                    argv_of(), self.timeout_s + extra_s, cancel=absent, cancellable=unsent
                )
            except BackendError as exc:
                self.events.add("estop", "error", f"E-STOP {what}: {exc}")
                return
            finally:
                if finished is not None:
                    finished.set()
            if absent is not None and absent.is_set() and run.stopped and unsent(run.out):
                self.events.add("estop", "info", f"E-STOP: the robot serves no {what}")
                return
            if run.returncode != 0 or run.stopped:
                why = run.err.strip()[-200:] or ("timed out" if run.stopped else "failed")
                if waited_for_service(run.out):
                    why = f"nothing answered it in {self.timeout_s + extra_s:g} s"
                self.events.add("estop", "error", f"E-STOP {what}: {why}")

        self.work.start(go, f"estop {what}")

    def _reap(self, proc: subprocess.Popen[str], what: str) -> None:
        try:
            rc = proc.wait(self.timeout_s)
        except Exception:  # noqa: BLE001
            ros2_process.stop(proc, 1.0)
            rc = None
        if rc != 0:
            err = (proc.stderr.read() or "").strip()[-200:] if proc.stderr else ""
            self.events.add("estop", "error", f"E-STOP {what}: {err or f'exit status {rc}'}")

    def release(self, *, robot: bool = True) -> list[str]:
        self.inflight.release()
        if self.armed is not None:
            self.armed.arm()
        name = self.live.name("release", RELEASE)  # under the robot's namespace
        spec = self.live.catalog.services.get(name)
        if spec is None or not robot:
            return []
        # a robot that latches its own stop lets go too
        run = self._run(["service", "call", name, spec.type, "{}"], self.timeout_s)
        if run.returncode == 0 and not run.stopped and not waited_for_service(run.out):
            return []
        why = f"release {name}: " + (run.err.strip()[-200:] or f"no answer in {self.timeout_s:g} s")
        self.events.add("estop", "error", why)
        return [why]
