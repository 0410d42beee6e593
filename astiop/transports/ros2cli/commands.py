"""The `ros2` transport's checked commands: each verb run by its means (a query, a message, a
sample of a topic, a goal followed to its end), and the goals' clients stopped."""

from __future__ import annotations

import re
import subprocess
import threading
from collections.abc import Callable
from typing import Any

from astiop.ros2.interfaces import decode_bytes
from astiop.ros2.printing import echo_text
from astiop.ros2.render import sent_argv
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import CALL, GOAL, SAMPLE, TAKE
from astiop.transports.base import BackendError, actuating, command_of
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import ENDED, InFlight
from astiop.transports.ros2cli import process as ros2_process
from astiop.transports.ros2cli.process import RunRos2
from astiop.transports.ros2cli.replies import (
    FAILED_WITH_STATUS_0,
    parse_response,
    waited_for_service,
    without_display_options,
)
from astiop.transports.ros2cli.streams import parse_document

Means = Callable[[Checked, list[str], float], tuple[str, Any]]  # how a verb's work is done


class CliCommands:
    """The checked commands run through `run` (`ros2 ARGV`); the goals' clients this process
    started, followed to their end, and how the last goal ended."""

    def __init__(self, run: RunRos2, executable: str, inflight: InFlight, events: EventLog):
        self._run = run
        self.executable = executable  # a goal's client is spawned here, not through `run`
        self.inflight = inflight
        self.events = events
        self.goal_procs: list[subprocess.Popen[str]] = []  # the goals' clients still running
        self.last_outcome: str | None = None  # how the last goal ended ("succeeded", ...)

    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        with actuating(
            self.inflight, checked
        ) as job:  # refused while the E-STOP holds, ended by it
            try:
                return self._execute(checked, timeout)
            except BackendError:
                if job is not None and job.ended_by_estop:
                    raise BackendError(f"{ENDED}: its ros2 process was killed") from None
                raise

    def _execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        verb = VERBS[command_of(checked).key]
        means: dict[str, Means] = {TAKE: self._echo, SAMPLE: self._sample, GOAL: self._send_goal}
        return means.get(verb.runs_as, self._once)(checked, sent_argv(checked), timeout)

    def _once(self, checked: Checked, argv: list[str], timeout: float) -> tuple[str, Any]:
        """A verb ros2 ends by itself: a query, a publish, a service call."""
        cmd = command_of(checked)
        verb = VERBS[cmd.key]
        if verb.duration is not None:  # never stop what validation allowed to run this long
            timeout += verb.duration(cmd)
        run = self._run(argv, timeout)
        calls = verb.runs_as == CALL
        if calls and waited_for_service(run.out):
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

    def _echo(self, checked: Checked, argv: list[str], timeout: float) -> tuple[str, Any]:
        # the robot is asked for whole values; the operator's display options (-l, --no-arr,
        # --no-str) shape only the text, made here from those values by echo_text
        argv = without_display_options(argv)
        if "--once" not in argv:
            argv.append("--once")
        argv.append("--full-length")
        run = self._run(argv, timeout, until=lambda out: "\n---" in out)
        cmd = command_of(checked)
        doc = parse_document(run.out.split("\n---", 1)[0].splitlines(keepends=True))
        if doc is None:
            if run.stopped:
                raise BackendError(f"no reading from {cmd.name} in {timeout:g} s")
            raise BackendError(run.err.strip()[:300] or f"no reading from {cmd.name}")
        if checked.type is not None:  # a checked echo has its topic's type
            doc = decode_bytes(checked.type, doc)
        return echo_text(doc, cmd), doc

    def _sample(self, checked: Checked, argv: list[str], timeout: float) -> tuple[str, Any]:
        """A verb ros2 runs until stopped (hz, bw): read until the verb has enough of it."""
        cmd = command_of(checked)
        verb = VERBS[cmd.key]
        if verb.parse_output is None:
            raise BackendError(f"ros2 {verb.name}: astiop does not read what it prints")
        run = self._run(argv, timeout, until=verb.output_complete)
        values = verb.parse_output(run.out)
        if values is None:
            raise verb.nothing_came(cmd.name or "", timeout)
        return run.out, values

    def _send_goal(self, checked: Checked, argv: list[str], timeout: float) -> tuple[str, Any]:
        """Return at acceptance; the client keeps running and is followed to the end."""
        name = command_of(checked).name or ""
        result = ros2_process.Run(argv)  # filled by the follower thread
        # a job of its own for the goal's life: the E-STOP stops its client, which cancels it
        goal = self.inflight.start(f"goal {name}", name=name)
        try:  # SIGINT, not a kill: its client cancels the goal on the robot
            proc = ros2_process.spawn_owned(self.executable, argv, goal, _stop_in_background)
        except BackendError:
            goal.done()
            raise
        accepted = threading.Event()
        stdout = proc.stdout
        assert stdout is not None  # spawn() pipes it

        def follow() -> None:
            for line in stdout:
                result.stdout.append(line)
                if "Goal accepted" in line or "Goal was rejected" in line:
                    accepted.set()
                m = re.match(r"Goal finished with status: (\w+)", line)
                if m:
                    self.last_outcome = m[1].lower()
                    self.events.add("goal", "info", f"goal finished: {m[1]}")
                elif line.startswith("Goal canceled."):
                    self.last_outcome = "canceled"
                    self.events.add("goal", "warning", "goal canceled")
            proc.wait()
            goal.done()
            accepted.set()
            if proc in self.goal_procs:
                self.goal_procs.remove(proc)

        self.goal_procs.append(proc)
        self.last_outcome = None
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
        """SIGINT each goal's client (it cancels its goal), without waiting for it to end."""
        for proc in list(self.goal_procs):
            _stop_in_background(proc)

    def close(self) -> None:
        """Each goal's client stopped, waited for (it cancels its goal on the robot)."""
        for proc in list(self.goal_procs):
            ros2_process.stop(proc, 3.0)


def _stop_in_background(proc: subprocess.Popen[str]) -> None:
    """SIGINT a goal's client (it cancels the goal), then harder, without waiting here."""
    threading.Thread(target=ros2_process.stop, args=(proc, 3.0), daemon=True).start()
