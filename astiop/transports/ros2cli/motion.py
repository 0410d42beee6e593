"""Publishers that must not pay the `ros2` start-up cost at the moment they matter.

Teleop: one long-lived `ros2 topic pub -r 10` per motion; a repeated key keeps it, a new
direction replaces it, and it lapses (then a zero Twist goes out) when the keys stop. The
lapse counts from when it is publishing ("publisher: beginning loop"), not from its spawn:
otherwise one key press would lapse before a slow CLI has started.

E-STOP: on distros whose `topic pub` takes `--stdin` (Jazzy on; ros2topic/verb/pub.py, jazzy
branch: values are read from stdin before the node is created), a publisher is started ahead
of time and waits on its stdin; the E-STOP writes the zero Twist and closes it, so the robot
gets it without the CLI's start-up delay. Humble's pub has no --stdin: there the zero Twist is
spawned on demand.
"""

from __future__ import annotations

import subprocess
import threading
import time
from collections.abc import Callable

from astiop.ros2.render import flow_yaml, stamped_now, velocity_message, zero_twist
from astiop.transports.ros2cli import process as ros2_process

STDIN_DISTROS = {"jazzy", "kilted", "rolling"}
TELEOP_RATE_HZ = 10
ESTOP_BURST = ("-r", "10", "-t", "10")  # a zero Twist at 10 Hz for 1 s


def zero_message(type_: str) -> dict:
    """A zero Twist in /cmd_vel's type, a TwistStamped stamped now."""
    return stamped_now(type_, velocity_message(type_, zero_twist()))


class TeleopPublisher:
    def __init__(
        self,
        executable: str,
        topic: str,
        type_: str,
        lapse_s: float = 0.5,
        on_lapse: Callable[[], None] | None = None,
    ):
        self.executable = executable
        self.on_lapse = on_lapse  # the keys stopped: nothing publishes until the next one
        self.topic = topic
        self.type = type_
        self.lapse_s = lapse_s
        self._lock = threading.Lock()
        self._proc: subprocess.Popen | None = None
        self._twist: dict | None = None
        self._ready = False
        self._deadline = 0.0
        self._closed = False
        self._watchdog = threading.Thread(target=self._watch, name="teleop-lapse", daemon=True)
        self._watchdog.start()

    def drive(self, twist: dict) -> None:
        with self._lock:
            if self._closed:
                return
            self._deadline = time.monotonic() + self.lapse_s
            if twist == self._twist and self._proc is not None and self._proc.poll() is None:
                return
            self._replace(twist)

    def _replace(self, twist: dict | None) -> None:
        old, self._proc, self._twist = self._proc, None, twist
        if old is not None:
            threading.Thread(target=ros2_process.stop, args=(old, 0.5), daemon=True).start()
        if twist is not None:
            argv = ["topic", "pub", "-r", str(TELEOP_RATE_HZ), self.topic, self.type]
            msg = stamped_now(self.type, velocity_message(self.type, twist))
            proc = ros2_process.spawn(self.executable, [*argv, flow_yaml(msg)])
            self._proc, self._ready = proc, False
            threading.Thread(target=self._drain, args=(proc,), daemon=True).start()

    def _drain(self, proc: subprocess.Popen) -> None:
        """Read what pub prints (a full pipe would block it) and note when it publishes."""
        assert proc.stdout is not None  # spawn() pipes it
        for line in proc.stdout:
            if line.startswith("publisher: beginning loop"):
                with self._lock:
                    if proc is self._proc:
                        self._ready = True
                        self._deadline = max(self._deadline, time.monotonic() + self.lapse_s)

    def _watch(self) -> None:
        while not self._closed:
            time.sleep(0.05)
            with self._lock:
                proc = self._proc
                starting = proc is not None and not self._ready and proc.poll() is None
                lapsed = proc is not None and not starting and time.monotonic() > self._deadline
                if lapsed:
                    self._replace(None)
                    if self.on_lapse is not None:  # before a new key can start a motion
                        self.on_lapse()
            if lapsed:  # motion lapsed: say so to the base too
                zero = zero_message(self.type)
                argv = ["topic", "pub", "--once", self.topic, self.type, flow_yaml(zero)]
                ros2_process.run(self.executable, argv, 10.0)

    def halt(self) -> None:
        """Kill the running publisher at once (E-STOP): nothing to cancel, no grace."""
        with self._lock:
            proc, self._proc, self._twist = self._proc, None, None
        if proc is not None and proc.poll() is None:
            proc.kill()

    def close(self) -> None:
        self._closed = True
        self.halt()


class ArmedStop:
    """A zero-Twist publisher started ahead of time, waiting on stdin (Jazzy and later)."""

    def __init__(self, executable: str, topic: str, type_: str):
        self.executable = executable
        self.argv = ["topic", "pub", "--stdin", *ESTOP_BURST, topic, type_]
        self.zero = zero_message(type_)
        self._proc: subprocess.Popen | None = None

    def arm(self) -> None:
        if self._proc is None or self._proc.poll() is not None:
            self._proc = ros2_process.spawn(self.executable, self.argv, stdin=True)

    def fire(self) -> subprocess.Popen | None:
        """Send the zero Twist now; None if no armed publisher was alive."""
        proc, self._proc = self._proc, None
        if proc is None or proc.poll() is not None or proc.stdin is None:
            return None
        try:
            proc.stdin.write(flow_yaml(self.zero) + "\n")
            proc.stdin.close()
        except OSError:
            return None
        return proc

    def disarm(self) -> None:
        proc, self._proc = self._proc, None
        if proc is not None and proc.poll() is None:
            proc.kill()  # never close its stdin: that would publish
