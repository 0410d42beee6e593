"""What this process has running that moves the robot (a timed publish, a goal's client, a teleop
hold, a subprocess), owned so that the E-STOP ends all of it before it sends its own stop.

Starting and stopping share one lock: a job is either refused because the E-STOP holds, or it is
registered before the E-STOP looks and ended by it. A job sends only inside `sending()`, under
its own lock, which its ending takes too: once `stop_all()` returns, none of them sends again.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from astiop.transports.errors import BackendError

HELD = "the E-STOP is engaged: nothing was sent"
ENDED = "the E-STOP ended it"


class Job:
    def __init__(
        self,
        owner: InFlight,
        what: str,
        on_end: Callable[[], None] | None = None,
        name: str = "",
    ):
        self.owner = owner
        self.what = what
        self.name = name  # the topic, service or action it moves the robot through
        self.lock = threading.RLock()
        self.ended_by_estop = False
        self._on_end = on_end
        self._ended = threading.Event()

    def on_estop(self, action: Callable[[], None]) -> None:
        """What ends this job's motion (kill its process, cancel its goal); run at once if the
        E-STOP already ended it."""
        with self.lock:
            self._on_end = action
            if self.ended_by_estop:
                action()
                raise BackendError(ENDED)

    @contextmanager
    def sending(self) -> Iterator[None]:
        """Send to the robot only if the E-STOP has not ended this job; it cannot end it
        meanwhile."""
        with self.lock:
            if self.ended_by_estop:
                raise BackendError(f"{ENDED}: publishing stopped")
            yield

    def wait(self, seconds: float) -> bool:
        """Sleep, woken by the E-STOP; True if it ended this job."""
        return self._ended.wait(seconds)

    def estop(self) -> str | None:
        with self.lock:
            self.ended_by_estop = True
            self._ended.set()
            action, self._on_end = self._on_end, None
            if action is None:
                return None
            try:
                action()
            except Exception as exc:  # noqa: BLE001 - the others are ended all the same
                return f"E-STOP could not end {self.what}: {exc}"
        return None

    def done(self) -> None:
        self.owner.done(self)


class InFlight:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._busy = threading.Condition(self._lock)
        self._jobs: list[Job] = []
        self._local = threading.local()
        self.held = False  # the E-STOP holds: nothing starts

    def start(self, what: str, on_estop: Callable[[], None] | None = None, name: str = "") -> Job:
        with self._lock:
            if self.held:
                raise BackendError(HELD)
            job = Job(self, what, on_estop, name)
            self._jobs.append(job)
            self._busy.notify_all()
            return job

    @contextmanager
    def running(self, what: str, name: str = "") -> Iterator[Job]:
        """A job for the duration of one command on this thread (`current()` finds it)."""
        job = self.start(what, name=name)
        self._local.job = job
        try:
            yield job
        finally:
            self._local.job = None
            job.done()

    def current(self, what: str = "") -> Job:
        """The job this thread is running a command for; else (a command that does not actuate)
        one of its own, which nothing ends."""
        return getattr(self._local, "job", None) or Job(self, what or "not an actuation")

    def current_job(self) -> Job | None:
        return getattr(self._local, "job", None)

    def done(self, job: Job) -> None:
        with self._lock:
            if job in self._jobs:
                self._jobs.remove(job)

    def stop_all(self) -> list[str]:
        """Hold (nothing starts from now on), then end every job; the failures."""
        with self._lock:
            self.held = True
            jobs, self._jobs = self._jobs, []
            self._busy.notify_all()
        return [f for f in (job.estop() for job in jobs) if f]

    def end_where(self, sent_to: Callable[[str], bool]) -> list[str]:
        """End the jobs whose name `sent_to` picks (another process's E-STOP of one robot of a
        fleet), holding nothing; the failures."""
        with self._lock:
            ended = [job for job in self._jobs if job.name and sent_to(job.name)]
            self._jobs = [job for job in self._jobs if job not in ended]
        return [f for f in (job.estop() for job in ended) if f]

    def release(self) -> None:
        with self._lock:
            self.held = False

    @property
    def busy(self) -> bool:
        return bool(self._jobs)

    @property
    def watched(self) -> bool:
        """Something to follow another process's latch for: a job that moves the robot, or the
        E-STOP this process holds (its release)."""
        return bool(self._jobs) or self.held

    def wait_watched(self, timeout_s: float) -> bool:
        """Block until `watched` (or `timeout_s`); whether it is."""
        with self._lock:
            return self._busy.wait_for(lambda: bool(self._jobs) or self.held, timeout_s)

    def wake(self) -> None:
        with self._lock:
            self._busy.notify_all()
