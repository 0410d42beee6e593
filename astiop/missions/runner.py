"""A mission run in a thread of its own, through the gateway, one step after the other: each
step starts only once the one before has ended as the robot reported it, and each end is stored
with the robot's pose. A failed step ends the mission with its reason; so do the E-STOP and a
cancel (from this process or, through the store, any other)."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from astiop.missions import follow
from astiop.missions.follow import StepEnd
from astiop.missions.steps import Step
from astiop.robot.gateway import RobotGateway
from astiop.store import Store, StoreError

log = logging.getLogger(__name__)
YES = lambda _c: True  # noqa: E731  (the operator approved the whole mission at its start)
STEP_TIMEOUT_S = 900.0
# a step that ended so ends the mission, with this status
ENDS_MISSION = {"e-stopped": "stopped", "canceled": "canceled"}


class MissionError(Exception):
    """A mission that cannot start or resume (one is running, nothing to resume, no steps)."""


@dataclass(frozen=True)
class StepReport:
    mission_id: int
    seq: int
    total: int
    label: str
    status: str
    detail: str

    def line(self) -> str:
        mark = {"succeeded": "✓", "skipped": "–"}.get(self.status, "✗")
        return (
            f"{mark} step {self.seq + 1}/{self.total} {self.label}: {self.status} — {self.detail}"
        )


OnStep = Callable[[StepReport], None]


def robot_key(gateway: RobotGateway) -> str:
    """Which robot a mission drives: one mission per robot at a time."""
    return gateway.label


class MissionRunner:
    """Starts, follows and cancels the missions of one robot (one at a time)."""

    def __init__(
        self,
        gateway: RobotGateway,
        store: Store,
        places: dict[str, tuple[float, float]] | None = None,
        on_step: OnStep | None = None,
        step_timeout_s: float = STEP_TIMEOUT_S,
    ):
        self.gateway = gateway
        self.store = store
        self.robot = robot_key(gateway)
        self._places = places
        self.on_step = on_step
        self.step_timeout_s = step_timeout_s
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        self.mission_id: int | None = None
        self.queue_only = False  # start() stores the mission for another process to drive

    # -- starting -------------------------------------------------------------------
    def start(self, steps: list[Step], request: str = "", source: str = "chat") -> int:
        if not steps:
            raise MissionError("a mission needs at least one step")
        self._refuse_if_running()
        mission_id = self.store.create_mission(
            self.robot,
            request,
            source,
            [(s.to_json(), s.label()) for s in steps],
            queued=self.queue_only,
        )
        self.mission_id = mission_id
        if not self.queue_only:
            self._launch(mission_id, steps, 0)
        return mission_id

    def resume(self, mission_id: int, from_step: int | None = None) -> int:
        """Go on with an interrupted mission from the step it was on (or `from_step`)."""
        self.store.mark_missions_interrupted()
        row = self.store.mission(mission_id)
        if row is None:
            raise MissionError(f"no mission {mission_id}")
        if row["status"] not in ("interrupted", "queued"):
            raise MissionError(f"mission {mission_id} is {row['status']}, not interrupted")
        rows = self.store.mission_steps(mission_id)
        steps = [Step.from_json(r["spec"]) for r in rows]
        start = row["step"] if from_step is None else from_step - 1
        if not 0 <= start < len(steps):
            raise MissionError(f"mission {mission_id} has steps 1 to {len(steps)}")
        self._refuse_if_running(this=mission_id)
        if not self.store.claim_mission(mission_id, start):
            raise MissionError(f"mission {mission_id} was resumed or dropped meanwhile")
        self._launch(mission_id, steps, start)
        return start

    def _refuse_if_running(self, this: int | None = None) -> None:
        if self.running:
            raise MissionError(f"mission {self.mission_id} is running on this robot")
        other = self.store.running_mission(self.robot)
        if other is not None and other["id"] != this:
            raise MissionError(
                f"mission {other['id']} is running on this robot (cancel it first: "
                f"astiop mission cancel {other['id']})"
            )

    def _launch(self, mission_id: int, steps: list[Step], start: int) -> None:
        self.mission_id = mission_id
        self._cancel.clear()
        self._thread = threading.Thread(
            target=self._run,
            args=(mission_id, steps, start),
            name=f"mission-{mission_id}",
            daemon=True,
        )
        self._thread.start()

    # -- control --------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout_s: float | None = None) -> bool:
        """Until the mission ends; False if it still runs after `timeout_s`."""
        if self._thread is not None:
            self._thread.join(timeout_s)
        return not self.running

    # -- the run --------------------------------------------------------------------
    def _run(self, mission_id: int, steps: list[Step], start: int) -> None:
        total = len(steps)
        status, reason = "succeeded", f"all {total} steps done"
        try:
            watcher = threading.Thread(target=self._watch_store, args=(mission_id,), daemon=True)
            watcher.start()
            for seq in range(start, total):
                step = steps[seq]
                self.store.step_started(mission_id, seq)
                end = self._step(step)
                pose, docked = self._where()
                self.store.step_ended(mission_id, seq, end.status, end.detail, pose, docked)
                if self.on_step:
                    self.on_step(
                        StepReport(mission_id, seq, total, step.label(), end.status, end.detail)
                    )
                if end.status in ("succeeded", "skipped"):
                    continue
                at = f"at step {seq + 1} of {total}"
                if end.status == "e-stopped":
                    reason = f"stopped by the E-STOP {at} ({step.label()})"
                elif end.status == "canceled":
                    reason = f"canceled by the operator {at} ({step.label()})"
                else:
                    reason = (
                        f"step {seq + 1} of {total} ({step.label()}) {end.status}: {end.detail}"
                    )
                status = ENDS_MISSION.get(end.status, "failed")
                break
        except StoreError as exc:
            status, reason = "failed", f"the store failed: {exc}"
            log.error("mission %s: %s", mission_id, exc)
        except Exception as exc:  # the mission ends, recorded, whatever went wrong
            status, reason = "failed", f"{type(exc).__name__}: {exc}"
            log.exception("mission %s failed", mission_id)
        finally:
            self._cancel.set()  # ends the store watcher
        try:
            self.store.finish_mission(mission_id, status, reason)
        except StoreError as exc:
            log.error("mission %s could not be recorded as %s: %s", mission_id, status, exc)

    def _watch_store(self, mission_id: int) -> None:
        """Another process (astiop mission cancel, the MCP server) asks through the store."""
        while not self._cancel.wait(0.5):
            try:
                if self.store.mission_cancel_requested(mission_id):
                    self._cancel.set()
            except StoreError:
                pass
            if self.gateway.e_stopped:
                return  # the step's own wait sees it and says so

    def _where(self) -> tuple[tuple[float, float, float] | None, bool | None]:
        state = self.gateway.state()
        pose = (state.pose.x, state.pose.y, state.pose.theta) if state.pose else None
        return pose, (state.status.docked if state.status else None)

    def places(self) -> dict[str, tuple[float, float]]:
        if self._places is not None:
            return self._places
        return {loc.name: (loc.x, loc.y) for loc in self.store.list_locations()}

    def _step(self, step: Step) -> StepEnd:
        if self._cancel.is_set():
            return StepEnd("canceled", "canceled by the operator before it started")
        if self.gateway.e_stopped:
            return StepEnd("e-stopped", "the E-STOP is engaged")
        if step.when is not None:
            value, text = follow.read(self.gateway, step.when.what)
            if value is None:
                return StepEnd("failed", text)
            if not step.when.holds(value):
                return StepEnd("skipped", f"{text}: not {step.when.text()}")
        if step.kind == "wait":
            return self._wait(step.seconds)
        if step.kind == "read":
            value, text = follow.read(self.gateway, step.what or "")
            return StepEnd("failed" if value is None else "succeeded", text)
        if step.kind in ("dock", "undock"):  # already so, as the robot reports: nothing to do
            status = self.gateway.state().status
            if status is not None and status.docked == (step.kind == "dock"):
                return StepEnd(
                    "skipped",
                    f"the robot reports it is {'' if status.docked else 'not '}docked already",
                )
        ex = self.gateway.run(step.command() or "", YES, source="mission")
        if not follow.accepted(ex):
            if ex.reason and "E-STOP" in ex.reason:
                return StepEnd("e-stopped", ex.reason)
            return StepEnd("failed", follow.refusal(ex))
        if not step.moves:  # load, unload: the service's reply is their end
            v = ex.values if isinstance(ex.values, dict) else {}
            return StepEnd("succeeded", str(v.get("message") or f"{step.kind} done"))
        target = None
        if step.kind == "goto":
            target = step.xy if step.xy is not None else self.places().get(step.place or "")
        return follow.follow_goal(self.gateway, step, target, self._cancel, self.step_timeout_s)

    def _wait(self, seconds: float) -> StepEnd:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            if self._cancel.wait(min(0.2, max(0.0, deadline - time.monotonic()))):
                return StepEnd("canceled", "canceled by the operator during the wait")
            if self.gateway.e_stopped:
                return StepEnd("e-stopped", "the E-STOP was pressed during the wait")
        return StepEnd("succeeded", f"waited {seconds:g} s")
