"""The MCP mission tools: start a mission (one approval shows every step), its status, cancel.
The mission runs in this server's process, through the gateway, like a console's."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from astiop.bounded import escape_controls, one_line
from astiop.mcp.approval import NO_CONSOLE, Policy, wait_for_decision
from astiop.mcp.audit import CALL
from astiop.mcp.refusals import Refused
from astiop.missions import view
from astiop.missions.runner import MissionError, MissionRunner
from astiop.missions.steps import KINDS, Condition, Step, describe

if TYPE_CHECKING:
    from astiop.robot.gateway import RobotGateway
    from astiop.store import Store

MAX_STEPS = 20
STEP_KEYS = {"kind", "place", "x", "y", "seconds", "what", "if"}


class MissionRefused(Exception):
    pass


def parse_steps(raw: Any, known: set[str]) -> list[Step]:
    """The client's steps, each checked; MissionRefused with the first thing wrong."""
    if not isinstance(raw, list) or not 1 <= len(raw) <= MAX_STEPS:
        raise MissionRefused(f"steps must be a list of 1 to {MAX_STEPS} steps")
    steps = []
    for n, item in enumerate(raw, 1):
        if not isinstance(item, dict) or not set(item) <= STEP_KEYS:
            raise MissionRefused(f"step {n}: an object with keys among {sorted(STEP_KEYS)}")
        try:
            steps.append(_step(item, known))
        except (TypeError, ValueError) as exc:
            raise MissionRefused(f"step {n}: {one_line(exc, 200)}") from None
    return steps


def _step(item: dict, known: set[str]) -> Step:
    kind = item.get("kind")
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(sorted(KINDS))}")
    when = None
    if item.get("if") is not None:
        c = item["if"]
        if not isinstance(c, dict) or c.get("op") not in ("<", ">"):
            raise ValueError("'if' is {what: battery|obstacles, op: '<'|'>', value: number}")
        when = Condition(str(c.get("what")), c["op"], _number(c.get("value"), "if.value"))
        if when.what not in ("battery", "obstacles"):
            raise ValueError("'if' reads battery or obstacles")
    place, xy = item.get("place"), None
    if kind == "goto":
        if place is not None:
            if not isinstance(place, str) or place not in known:
                raise ValueError(f"no location named {escape_controls(str(place))[:64]}")
        else:
            xy = (_number(item.get("x"), "x"), _number(item.get("y"), "y"))
    seconds = _number(item.get("seconds", 0.0), "seconds")
    what = item.get("what")
    return Step(kind, place=place, xy=xy, seconds=seconds, what=what, when=when)


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or abs(value) > 1e6:
        raise ValueError(f"{name} must be a finite number")
    return float(value)


class MissionTools:
    """Mixed into RobotTools: uses its gateway, store, policy and name."""

    gateway: RobotGateway
    store: Store
    policy: Policy
    name: str
    _runner: MissionRunner | None = None

    def _missions(self) -> MissionRunner:
        if self._runner is None:
            self._runner = MissionRunner(self.gateway, self.store)
        return self._runner

    def start_mission(
        self, steps: list[dict], replace: bool = False, until_stopped: bool = False
    ) -> str:
        known = {loc.name for loc in self.store.list_locations()}
        try:
            parsed = parse_steps(steps, known)
        except MissionRefused as exc:
            raise Refused(str(exc)) from None
        for n, step in enumerate(parsed, 1):
            command = step.command()
            review = self.gateway.review(command) if command else None
            if review is not None and not (review.checked.valid and review.allowed):
                why = review.reason or review.checked.reason
                raise Refused(f"step {n} ({step.label()}): {why}; nothing was sent")
        plan = describe(parsed, until_stopped)
        runner = self._missions()
        live = runner.live_mission()
        if live is not None and not replace:
            raise Refused(
                f"{view.live_text(self.store, live['id'])}: one mission per robot. Call "
                "start_mission with replace: true to replace it, or cancel_mission first; "
                "nothing was sent"
            )
        replaces = ""
        if live is not None and (m := view.as_json(self.store, live["id"])) is not None:
            replaces = f"It replaces mission {m['id']} ({m['status']}: {view.where(m)})."
        self._approve_mission(plan, replaces)
        self.gateway.start()
        try:
            mission_id = runner.start(
                parsed,
                plan,
                source="mcp",
                forever=until_stopped,
                replace=live["id"] if live is not None else None,
            )
        except MissionError as exc:
            raise Refused(str(exc)) from None
        said = f" It replaced mission {live['id']}." if live is not None else ""
        return (
            f"mission {mission_id} started: {len(parsed)} step{'s' * (len(parsed) != 1)} — {plan}. Each step starts when "
            f"the one before has ended; mission_status reports them as the robot did them.{said}"
        )

    def _approve_mission(self, plan: str, replaces: str = "") -> None:
        if self.gateway.e_stopped:
            raise Refused("the E-STOP is engaged: nothing was sent")
        if self.policy.approve_actuation:
            return
        if not self.store.console_open():
            raise Refused(NO_CONSOLE)
        call = CALL.get()
        detail = f"MCP client '{call.client}' asks for a mission of every step below:\n{plan}"
        if replaces:
            detail += f"\n{replaces}"
        what = f"mission: {plan}" + (f" ({replaces.rstrip('.')})" if replaces else "")
        request = self.store.request_approval(
            call.client, what, detail, self.policy.timeout_s, robot=self.name
        )
        status = wait_for_decision(self.store, request, self.policy.timeout_s)
        if status == "denied":
            raise Refused("denied by the operator")
        if status != "approved":
            raise Refused(f"no answer from the operator within {self.policy.timeout_s:g} s")

    def mission_status(self, mission_id: int = 0) -> dict:
        if mission_id == 0:
            row = self.store.latest_mission()
            if row is None:
                raise Refused("no mission yet")
            mission_id = row["id"]
        m = view.as_json(self.store, mission_id)
        if m is None:
            raise Refused(f"no mission {mission_id}")
        return {**m, "summary": view.summary(m)}

    def cancel_mission(self, mission_id: int = 0) -> str:
        row = self.store.running_mission(self._missions().robot)
        if mission_id == 0:
            if row is None:
                raise Refused("no mission is running")
            mission_id = row["id"]
        before = self.store.request_mission_cancel(mission_id)
        if before is None:
            raise Refused(f"no mission {mission_id}")
        if before not in ("running", "paused", "interrupted", "queued"):
            raise Refused(f"mission {mission_id} is {before}: nothing to cancel")
        runner = self._missions()
        if runner.mission_id == mission_id and runner.running:
            runner.cancel()
            runner.wait(30)
        m = view.as_json(self.store, mission_id)
        return view.summary(m) if m else f"mission {mission_id}: cancel asked"
