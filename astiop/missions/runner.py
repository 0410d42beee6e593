"""A mission run in a thread of its own, through the gateway, one step after the other: each
step starts only once the one before has ended as the robot reported it, and each end is stored
with the robot's pose. A failed step ends the mission with its reason; so do the E-STOP, a
cancel and a replacing mission (from this process or, through the store, any other). A pause
holds the robot between two steps; a mission repeated until stopped starts over after its last
step, round after round, until canceled (a failed step still ends it: never repeated)."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from astiop.missions import follow, view
from astiop.missions.follow import StepEnd, StepReport, as_replaced
from astiop.missions.steps import Step
from astiop.robot.gateway import RobotGateway
from astiop.store import Store, StoreError
from astiop.store.missions import LIVE

log = logging.getLogger(__name__)
YES = lambda _c: True  # noqa: E731  (the operator approved the whole mission at its start)
STEP_TIMEOUT_S = 900.0
REPLACE_WAIT_S = 30.0  # for the replaced mission's process to end it (its step's goal too)
MIN_ROUND_S = 1.0  # a repeat until stopped never spins faster than this
# a step that ended so ends the mission, with this status
ENDS_MISSION = {"e-stopped": "stopped", "canceled": "canceled"}


class MissionError(Exception):
    """A mission that cannot start or resume (one is running, nothing to resume, no steps)."""

    def __init__(self, text: str, running: int | None = None):
        super().__init__(text)
        self.running = running  # the mission in the way, when another one runs on this robot


OnStep = Callable[[StepReport], None]


def robot_key(gateway: RobotGateway) -> str:
    """Which robot a mission drives: one mission per robot at a time."""
    return gateway.label


class MissionRunner:
    """Starts, follows, pauses and cancels the missions of one robot (one at a time)."""

    def __init__(
        self,
        gateway: RobotGateway,
        store: Store,
        places: dict[str, tuple[float, float]] | None = None,
        on_step: OnStep | None = None,
        step_timeout_s: float = STEP_TIMEOUT_S,
        on_note: Callable[[str], None] | None = None,
    ):
        self.gateway = gateway
        self.store = store
        self.robot = robot_key(gateway)
        self._places = places
        self.on_step = on_step
        self.on_note = on_note  # paused, going on: said where a caller follows the mission
        self.step_timeout_s = step_timeout_s
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        self.mission_id: int | None = None
        self.queue_only = False  # start() stores the mission for another process to drive
        self._known: set[str] = set()  # the places of the mission driven, when it was launched

    # -- starting -------------------------------------------------------------------
    def start(
        self,
        steps: list[Step],
        request: str = "",
        source: str = "chat",
        *,
        forever: bool = False,
        replace: int | None = None,
    ) -> int:
        """A new mission; `replace`: the running mission the operator agreed it replaces (it
        ends as 'replaced by mission M' before the first step of this one starts)."""
        if not steps:
            raise MissionError("a mission needs at least one step")
        other = self.live_mission()
        if other is not None and other["id"] != replace:
            raise MissionError(self._in_the_way(other["id"]), other["id"])
        mission_id = self.store.create_mission(
            self.robot,
            request,
            source,
            [(s.to_json(), s.label()) for s in steps],
            queued=self.queue_only or other is not None,
            forever=forever,
        )
        self.mission_id = mission_id
        if other is not None:
            self._replace(other["id"], mission_id)
            if not self.queue_only and not self.store.claim_mission(mission_id, 0):
                raise MissionError(f"mission {mission_id} was dropped meanwhile")
        if not self.queue_only:
            self._launch(mission_id, steps, 0, forever, 1)
        return mission_id

    def live_mission(self) -> dict | None:
        """The mission running (or paused, or queued) on this robot, if any."""
        if self.running and self.mission_id is not None:
            return self.store.mission(self.mission_id)
        return self.store.running_mission(self.robot)

    def _in_the_way(self, other: int) -> str:
        return view.live_text(self.store, other)

    def _replace(self, old: int, new: int) -> None:
        """End mission `old` as replaced by `new`, the way a cancel ends it, and wait for its
        end; MissionError (and `new` failed, nothing sent) if it does not end in time."""
        before = self.store.request_mission_replace(old, new)
        if before not in ("running", "paused"):
            return  # ended meanwhile, or queued and replaced at once
        mine = self.running and self.mission_id == old
        if mine:
            self._cancel.set()
        deadline = time.monotonic() + REPLACE_WAIT_S
        while time.monotonic() < deadline:
            if mine and self._thread is not None:
                self._thread.join(0.2)
            else:
                time.sleep(0.2)
            self.store.mark_missions_interrupted()
            row = self.store.mission(old)
            if row is None or row["status"] not in LIVE:
                return
        why = f"mission {old} did not end within {REPLACE_WAIT_S:g} s; nothing was sent"
        self.store.finish_mission(new, "failed", why)
        raise MissionError(why, old)

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
        other = self.live_mission()
        if other is not None and other["id"] != mission_id:
            raise MissionError(self._in_the_way(other["id"]), other["id"])
        if not self.store.claim_mission(mission_id, start):
            raise MissionError(f"mission {mission_id} was resumed or dropped meanwhile")
        self._launch(
            mission_id, steps, start, bool(row["forever"]), row["round"] or 1, resumed=True
        )
        return start

    def _launch(
        self,
        mission_id: int,
        steps: list[Step],
        start: int,
        forever: bool,
        round_: int,
        resumed: bool = False,
    ) -> None:
        self.mission_id = mission_id
        # the named places the mission goes to, as they are now: one removed meanwhile is
        # refused when its step starts (a place the locations never held is the robot's to know)
        self._known = {s.place for s in steps if s.place and s.place in self.places()}
        self._cancel = threading.Event()  # each mission its own: an old watcher cannot reach it
        self._thread = threading.Thread(
            target=self._run,
            args=(mission_id, steps, start, forever, round_, resumed),
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
    def _run(
        self,
        mission_id: int,
        steps: list[Step],
        seq: int,
        forever: bool,
        round_: int,
        resumed: bool = False,
    ) -> None:
        total = len(steps)
        status, reason = "succeeded", f"all {total} steps done"
        try:
            watcher = threading.Thread(
                target=self._watch_store, args=(mission_id, self._cancel), daemon=True
            )
            watcher.start()
            round_t0 = time.monotonic()
            while True:
                step = steps[seq]
                self.store.step_started(mission_id, seq)
                end = self._step(step)
                by = self.store.mission_requests(mission_id)["replaced_by"]
                if end.status == "canceled" and by:
                    end = as_replaced(end, by)
                if resumed and end.status == "failed" and not end.sent:
                    status, reason = self._resume_refused(mission_id, seq, total, step, end)
                    break
                resumed = False  # a step of this run reached the robot
                pose, docked = self._where()
                self.store.step_ended(mission_id, seq, end.status, end.detail, pose, docked)
                if self.on_step:
                    self.on_step(
                        StepReport(
                            mission_id, seq, total, step.label(), end.status, end.detail,
                            round_ if forever else None,
                        )
                    )  # fmt: skip
                if end.status not in ("succeeded", "skipped"):
                    shown = round_ if forever else 0
                    status, reason = self._ended(end, seq, total, step, shown, by)
                    break
                seq += 1
                if seq == total:
                    if not forever:
                        break
                    # a round of skipped steps must not spin: at least MIN_ROUND_S each
                    rest = MIN_ROUND_S - (time.monotonic() - round_t0)
                    if rest > 0:
                        self._cancel.wait(rest)
                    seq, round_, round_t0 = 0, round_ + 1, time.monotonic()
                    self.store.new_round(mission_id, round_)
                held = self._hold_if_paused(mission_id, seq, total, steps[seq].label())
                if held is not None:
                    status, reason = held
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

    def _resume_refused(
        self, mission_id: int, seq: int, total: int, step: Step, end: StepEnd
    ) -> tuple[str, str]:
        """A resume whose first step was refused with nothing sent (another holds the robot,
        the robot unreached): the mission stays interrupted at that step, to be resumed again."""
        reason = (
            f"resume refused at step {seq + 1} ({step.label()}): {end.detail}; nothing was "
            f"sent: `astiop mission resume {mission_id}` again once that is settled"
        )
        self.store.step_ended(mission_id, seq, "interrupted", end.detail, None, None)
        if self.on_step:
            self.on_step(StepReport(mission_id, seq, total, step.label(), "refused", reason))
        return "interrupted", reason

    def _ended(
        self, end: StepEnd, seq: int, total: int, step: Step, round_: int, by: int | None
    ) -> tuple[str, str]:
        """How a step that did not succeed ends the mission: (status, reason)."""
        at = f"at step {seq + 1} of {total}" + (f" in round {round_}" if round_ else "")
        done = f"; {round_ - 1} round{'s' * (round_ != 2)} done" if round_ else ""
        if end.status == "e-stopped":
            return "stopped", f"stopped by the E-STOP {at} ({step.label()}){done}"
        if end.status == "canceled":
            return "canceled", f"canceled by the operator {at} ({step.label()}){done}"
        if end.status == "replaced" and by:
            return "replaced", f"replaced by mission {by} {at} ({step.label()}){done}"
        status = ENDS_MISSION.get(end.status, "failed")
        where = f"step {seq + 1} of {total}" + (f" in round {round_}" if round_ else "")
        return status, f"{where} ({step.label()}) {end.status}: {end.detail}{done}"

    def _hold_if_paused(
        self, mission_id: int, seq: int, total: int, label: str
    ) -> tuple[str, str] | None:
        """A pause asked (through the store, from any process) holds the robot here, between
        the step that ended and the next, until resumed; (status, reason) if the mission ends
        while held (cancel, replacement, E-STOP), None when it goes on."""
        if not self.store.mission_requests(mission_id)["pause"]:
            return None
        before = f"before step {seq + 1} of {total} ({label})"
        self.store.mission_held(mission_id, True, seq, f"paused by the operator {before}")
        self._note(f"mission {mission_id} paused {before}")
        while True:
            if self._cancel.wait(0.25):
                by = self.store.mission_requests(mission_id)["replaced_by"]
                if by:
                    return "replaced", f"replaced by mission {by} while paused {before}"
                return "canceled", f"canceled by the operator while paused {before}"
            if self.gateway.e_stopped:
                return "stopped", f"stopped by the E-STOP while paused {before}"
            if not self.store.mission_requests(mission_id)["pause"]:
                self.store.mission_held(mission_id, False, seq, "")
                self._note(f"mission {mission_id} goes on with step {seq + 1} of {total}")
                return None

    def _note(self, text: str) -> None:
        if self.on_note is not None:
            self.on_note(text)

    def _watch_store(self, mission_id: int, cancel: threading.Event) -> None:
        """Another process (astiop mission cancel, the MCP server) asks through the store."""
        while not cancel.wait(0.5):
            try:
                if self.store.mission_cancel_requested(mission_id):
                    cancel.set()
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
        if step.kind == "goto" and step.place in self._known and step.place not in self.places():
            return StepEnd(
                "failed",
                f"the place '{step.place}' was removed from this map's locations during the mission: "
                "nothing was sent",
                sent=False,
            )
        command = step.command(self.gateway.profile, self.places().get)
        if command is None:
            return StepEnd("failed", f"this robot cannot {step.label()} (`astiop robot profile`)")
        ex = self.gateway.run(command, YES, source="mission")
        if not follow.accepted(ex):
            if ex.reason and "E-STOP" in ex.reason:
                return StepEnd("e-stopped", ex.reason)
            return StepEnd("failed", follow.refusal(ex), sent=ex.executed)
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
