"""The one door to the robot: validate, review for safety, confirm, execute, record the result."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Protocol

from astiop.robot.catalog import Catalog
from astiop.robot.output import BackendError, Execution
from astiop.robot.safety import Review, SafetyPolicy
from astiop.robot.validation import Checked, validate

Confirm = Callable[[Checked], bool]


class RobotBackend(Protocol):
    name: str
    catalog: Catalog

    @property
    def e_stopped(self) -> bool: ...

    def estop(self) -> None: ...

    def release_estop(self) -> None: ...

    def execute(self, checked: Checked, timeout: float) -> tuple[str, object]: ...


class RobotGraph:
    def __init__(
        self, backend: RobotBackend, safety: SafetyPolicy | None = None, timeout_s: float = 10.0
    ):
        self.backend = backend
        self.safety = safety or SafetyPolicy()
        self.timeout_s = timeout_s

    @property
    def catalog(self) -> Catalog:
        return self.backend.catalog

    @property
    def e_stopped(self) -> bool:
        return self.backend.e_stopped

    def estop(self) -> None:
        self.backend.estop()

    def release_estop(self) -> None:
        self.backend.release_estop()

    def wait_until_idle(self, timeout_s: float) -> None:
        """Block until the robot has no active goal (or the timeout); backends may lack it."""
        wait = getattr(self.backend, "wait_until_idle", None)
        if wait is not None:
            wait(timeout_s)

    def review(self, text: str) -> Review:
        return self.safety.review(validate(text, self.catalog), self.backend.e_stopped)

    def run(
        self, text: str, confirm: Confirm | None = None, timeout: float | None = None
    ) -> Execution:
        """Run one command. Nothing reaches the backend unless it is valid, safe and confirmed."""
        t0 = time.perf_counter()
        review = self.review(text)
        checked = review.checked
        result = Execution(
            text.strip(), checked.valid, checked.reason, checked.kind, notes=list(checked.notes)
        )
        if not review.allowed:
            result.reason = review.reason
            return result
        if review.needs_confirmation:
            if confirm is None:
                result.reason = "this command moves the robot and needs the operator's confirmation"
                return result
            if not confirm(checked):
                result.reason = "not confirmed by the operator"
                return result
        try:
            result.output, result.values = self.backend.execute(checked, timeout or self.timeout_s)
            result.executed = True
        except BackendError as exc:
            result.executed = True
            result.error = str(exc)
            result.output = f"error: {exc}\n"
        self._after(checked, result)
        result.duration_s = time.perf_counter() - t0
        return result

    def _after(self, checked: Checked, result: Execution) -> None:
        cmd = checked.command
        if result.error or cmd.key != ("param", "set"):
            return
        if cmd.args["param"] == "max_linear_speed":
            self.safety.max_linear = checked.message["value"]
        elif cmd.args["param"] == "max_angular_speed":
            self.safety.max_angular = checked.message["value"]
