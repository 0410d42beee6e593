"""The `ros2` transport's checked commands: each verb run by its means (a query, a message, a
sample of a topic, a goal followed to its end), and the goals' clients stopped."""

from __future__ import annotations

import re
import threading
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any, Protocol

from astiop.ros2.interfaces import decode_bytes
from astiop.ros2.printing import echo_text
from astiop.ros2.render import sent_argv
from astiop.ros2.validation import Checked
from astiop.ros2.verbs import VERBS
from astiop.ros2.verbs.base import CALL, GOAL, SAMPLE, TAKE
from astiop.transports.base import BackendError
from astiop.transports.event_log import EventLog
from astiop.transports.inflight import ENDED, InFlight, Job
from astiop.transports.ros2cli import process as ros2_process
from astiop.transports.ros2cli.replies import (
    FAILED_WITH_STATUS_0,
    parse_response,
    waited_for_service,
    without_display_options,
)
from astiop.transports.ros2cli.streams import parse_document


class CliCommandsHost(Protocol):
    """What `CliCommands` needs of the backend it is mixed into."""

    executable: str
    inflight: InFlight
    events: EventLog
    _goal_procs: list[Any]
    _last_outcome: str | None

    def actuating(self, checked: Checked) -> AbstractContextManager[Job | None]: ...

    def _run(self, argv: list[str], timeout: float, **kw) -> ros2_process.Run: ...


if TYPE_CHECKING:
    _Host = CliCommandsHost
else:
    _Host = object


class CliCommands(_Host):
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
        cmd, verb = checked.command, VERBS[checked.command.key]
        if verb.lasts is not None:  # never stop what validation allowed to run this long
            timeout += verb.lasts(cmd)
        run = self._run(argv, timeout)
        calls = verb.means == CALL
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
            raise verb.nothing_came(checked.command.name, timeout)
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
