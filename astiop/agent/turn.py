"""One agent turn: plan commands with the model (`planner`), check and run them, explain the
results (`interpretation`), the interaction written to the store as it goes (`recorder`).

Only the planning reply, written before any robot output is seen, is turned into commands; the
interpretation reply never is. So nothing a robot prints can make a command run. The intent
gate (`gate`) holds the plan to what the request asked before anything runs, and the answer is
held to what the robot reported (`grounding`).
"""

from __future__ import annotations

import asyncio
import functools
import time
from collections.abc import Callable
from typing import Any

from astiop.agent import (
    gate,
    goals,
    intent,
    local_save,
    mission_turn,
    planner,
    roles,
    rules,
    subject,
    subject_answers,
    view,
    warm,
    watch_turn,
)
from astiop.agent.intent import Intent
from astiop.agent.interpretation import Interpreter
from astiop.agent.models.llm import LLMError, LLMHTTPError, LLMTimeout, LLMUnavailable
from astiop.agent.models.reply_stream import Completion
from astiop.agent.models.specs import LLMEndpoint
from astiop.agent.recorder import Recorder
from astiop.agent.result import TurnResult
from astiop.missions.runner import MissionRunner
from astiop.robot.gateway import Confirm, RobotGateway
from astiop.robot.safety import Review
from astiop.store import Store
from astiop.transports.base import Execution
from astiop.warehouse import WarehouseMap

OnEvent = Callable[[str, Any], None]  # ("plan_token" | "command" | "answer_token" | "status", x)
HISTORY_TURNS = 3
DEADLINE_S = 120.0  # no reply streams longer than this, whatever the server does


class Agent:
    def __init__(
        self,
        gateway: RobotGateway,
        endpoint: LLMEndpoint,
        store: Store | None = None,
        *,
        mode: str = "tool",
        max_tokens: int = 256,
        confirm: Confirm | None = None,
        session: str = "",
        nav_wait_s: float = 600.0,
        fallback: bool = True,
        places: dict[str, tuple[float, float]] | None = None,
        interpretation: str = "grounded",
        interpret_tokens: int = 96,
        narrow_tools: bool = True,
        missions: MissionRunner | None = None,
        confirm_mission: mission_turn.ConfirmMission | None = None,
        replace_mission: mission_turn.ReplaceMission = None,
        robot: str = "",
        confirm_reaction: watch_turn.ConfirmReaction | None = None,
    ):
        self.interpreter = Interpreter(self._ask, interpretation, interpret_tokens)
        _check_mode(endpoint, mode)
        self.gateway = gateway
        self.endpoint = endpoint
        self.store = store
        self.recorder = Recorder(store, session)
        self._reviews: dict[str, Review] = {}  # this turn's commands, each validated once
        self.mode = "rules" if endpoint.is_rules else mode
        self.max_tokens = max_tokens
        self.confirm = confirm
        self.nav_wait_s = nav_wait_s
        self.history: list[tuple[str, str]] = []
        self.fallback = fallback  # the rules answer when the model is unreachable
        self._places = places
        self._turn_places: dict[str, tuple[float, float]] | None = None
        self.narrow_tools = narrow_tools
        self._schema_ok = True
        self._missions, self.confirm_mission = missions, confirm_mission
        self.replace_mission = replace_mission  # a new mission while one runs: ask, or not
        self.confirm_reaction = confirm_reaction  # a watch's reaction that moves the robot
        self.robot = robot  # its name in a fleet

    @property
    def missions(self) -> MissionRunner | None:
        """The runner of this robot's missions (None without a store: a mission is stored)."""
        if self._missions is None and self.store is not None:
            self._missions = MissionRunner(self.gateway, self.store)
        return self._missions

    @property
    def model(self) -> str:
        return self.endpoint.spec.raw

    def switch(self, endpoint: LLMEndpoint | None = None, mode: str | None = None) -> None:
        """Another model or reply mode for the turns to come (the conversation goes on)."""
        endpoint, mode = endpoint or self.endpoint, mode or self.mode
        _check_mode(endpoint, mode)
        if endpoint is not self.endpoint:
            self.endpoint, self._schema_ok = endpoint, True  # the new server may take a schema
        self.mode = "rules" if endpoint.is_rules else mode

    def places(self) -> dict[str, tuple[float, float]]:
        """The named locations' x, y, read once per turn (planning, gate and goal all ask)."""
        if self._places is not None:
            return self._places
        if self._turn_places is None:
            if self.store is not None:
                found = {loc.name: (loc.x, loc.y) for loc in self.store.list_locations()}
            else:
                geometry = self.gateway.map_geometry()
                stations = geometry.stations if isinstance(geometry, WarehouseMap) else ()
                found = {s.name: s.pose[:2] for s in stations}
            self._turn_places = found
        return self._turn_places

    def locations(self) -> list[str]:
        return list(self.places())

    def _review(self, command: str) -> Review:
        """Validation and safety for one command, once per turn."""
        if command not in self._reviews:
            self._reviews[command] = self.gateway.review(command)
        return self._reviews[command]

    def gate_reason(self, request: str, commands: list[str]) -> str | None:
        """Why the plan does not do what the request asks; None when it does."""
        return self._gate_reason(intent.classify(request, self.locations()), commands)

    def _gate_reason(self, intents: list[Intent], commands: list[str]) -> str | None:
        checks = [self._review(c).checked for c in commands]
        if other := gate.other_robot(checks, self.gateway.catalog):
            return other
        actions = [(c, gate.action_of(ch)) for c, ch in zip(commands, checks, strict=True)]
        return gate.check(intents, actions, self.places())

    def _rules_plan(self, intents: list[Intent]) -> list[str]:
        return rules.plan_intents(intents, self.gateway.profile, self.places().get)

    # -- the turn ------------------------------------------------------------------------
    async def turn(self, request: str, on_event: OnEvent | None = None) -> TurnResult:
        emit = on_event or (lambda kind, data: None)
        t0 = time.perf_counter()
        result = TurnResult(self.model, self.mode, request, robot=self.robot)
        self._reviews, self._turn_places = {}, None  # this turn reads them afresh
        await self.recorder.start(result)
        try:
            # classified once: the planner narrows the tools by it, the gate holds plans to it
            profile = self.gateway.profile  # on half a graph (a new process: astiop chat), a
            if profile.pending() or profile.make == "unknown":  # role or the make is missing:
                await asyncio.to_thread(self.gateway.confirm_missing)  # read it whole first
            if said := await asyncio.to_thread(watch_turn.kept, request, self):  # a watch
                result.answer = said
                return await self._finish(request, result, t0)
            intents = intent.classify(request, self.locations())
            asked = subject.subjects_of(
                request, intents, self.locations(), unknown=not self.endpoint.is_rules
            )
            if asked:
                await self._answer_subjects(asked, result, emit)  # its reads, no model
                return await self._finish(request, result, t0)
            if said := await self._unless_discovered(
                lambda: (
                    roles.nothing_to_read(intents, self.gateway.profile)
                    or local_save.unknown_place(request, intents, self.gateway.profile, self.store)
                )
            ):  # asked only of readings this robot does not publish, or of a place its map
                result.answer = said  # does not hold on a robot that cannot look it up
                return await self._finish(request, result, t0)
            place = local_save.asked(intents, self.gateway.profile)
            if place and self.store is not None:  # no save service: kept in astiop's store
                ex, result.answer = await asyncio.to_thread(
                    local_save.save_here, self.gateway, self.store, place
                )
                result.commands += [ex] if ex is not None else []
                return await self._finish(request, result, t0)
            if await mission_turn.without_model(self, request, intents, result, emit):
                return await self._finish(request, result, t0)
            commands = warm.readings_meanwhile(self.endpoint, intents, self._rules_plan)
            fallback = warm.WARMING if commands else ""  # who answers, when not the model
            try:
                commands = commands or await self._plan(request, intents, result, emit)
            except (LLMUnavailable, LLMTimeout, LLMHTTPError) as exc:
                _keep_partial(result, exc)
                unavailable = not isinstance(exc, LLMHTTPError) or exc.status in (502, 503, 504)
                if not self.fallback or not unavailable:
                    raise
                # the baseline answers instead, labelled so; the turn still records the error
                result.error = f"{exc}; answered by the rules fallback"
                commands, fallback = self._rules_plan(intents), "[rules fallback] "
            refused = await asyncio.to_thread(self._gate_reason, intents, commands)
            steps = None
            if not refused and self.missions is not None:
                steps, refused = await asyncio.to_thread(
                    mission_turn.plan_as_mission, request, commands, self._review, self.places()
                )
            if refused:
                await self._refuse(commands, refused, result, emit)
            elif steps:
                await mission_turn.begin(self, request, steps, result, emit)
            else:
                await self._execute(commands, result, emit)
                result.answer = await self.interpreter.interpret(
                    self.endpoint, request, result, emit, fallback
                )
        except LLMError as exc:
            _keep_partial(result, exc)
            result.error = str(exc)
            if not result.answer:
                result.answer = f"The model could not answer: {exc}"
        except asyncio.CancelledError:
            result.error = "canceled by the operator"
            result.total_s = time.perf_counter() - t0
            self.recorder.finish_now(result, status="canceled")
            raise
        except Exception as exc:  # recorded, then reported by the caller's one handler
            result.error = f"{type(exc).__name__}: {exc}"
            result.total_s = time.perf_counter() - t0
            self.recorder.finish_now(result, status="error")
            raise
        return await self._finish(request, result, t0)

    async def _answer_subjects(self, asked: list, result: TurnResult, emit) -> None:
        """A question's subject answered from the reads it takes, computed, for every model."""
        reads, places = subject_answers.Reads(self.gateway), self.places()
        texts = [  # but the view: a model that sees says it from the camera's frame (`view`)
            await view.answer(result.prompt, reads, self.endpoint, self._ask, result, emit)
            if s.kind == "view"
            else await asyncio.to_thread(subject_answers.answer, s, reads, places, self.store)
            for s in asked
        ]
        for seq, ex in enumerate(reads.ran):
            result.commands.append(ex)
            await self.recorder.command(result, seq, ex)
            emit("command", ex)
        result.grounding = "subject: " + ", ".join(s.kind for s in asked)
        result.answer = ("[rules] " if self.endpoint.is_rules else "") + " ".join(texts)
        emit("answer_token", result.answer)

    async def _unless_discovered(self, missing) -> str:
        """`missing()`'s answer, said only once the robot's graph has been read whole."""
        said = missing()
        if said:  # a process still discovering the robot reads its graph again first
            await asyncio.to_thread(self.gateway.confirm_missing)
            said = missing()
        return said

    async def _finish(self, request: str, result: TurnResult, t0: float) -> TurnResult:
        result.total_s = time.perf_counter() - t0
        await self.recorder.finish(result)
        self.history.append((request, result.answer))
        return result

    async def _account(self, result: TurnResult, c: Completion) -> None:
        result.raw_replies.append(c.text)
        result.llm_s += c.total_s
        result.prompt_tokens += c.prompt_tokens or 0
        result.completion_tokens += c.completion_tokens or 0
        result.ttft_s = c.ttft_s if result.ttft_s is None else result.ttft_s
        await self.recorder.replies(result)

    async def _ask(
        self,
        messages,
        schema,
        result: TurnResult,
        emit,
        kind: str,
        grammar: str | None = None,
        max_tokens: int | None = None,
    ) -> Completion:
        client = await asyncio.to_thread(self.endpoint.client)
        on_token = functools.partial(emit, kind)
        if not self.endpoint.local:
            grammar = None  # GBNF is llama.cpp's; other servers get the JSON schema
        limits = {
            "max_tokens": max_tokens or self.max_tokens,
            "guard": True,
            # llama.cpp's repeat penalties keep a free answer from looping, but under the
            # answer grammar they push a small model off the very figures it must copy
            "penalties": kind == "answer_token" and self.endpoint.local and grammar is None,
            "deadline_s": DEADLINE_S,
        }
        try:
            c = await client.chat(
                messages,
                on_token=on_token,
                schema=schema if self._schema_ok else None,
                grammar=grammar,
                **limits,
            )
        except LLMHTTPError as exc:
            if schema is None or exc.status not in (400, 422, 501) or not self._schema_ok:
                raise
            self._schema_ok = False  # this server does not take a JSON schema
            c = await client.chat(messages, on_token=on_token, **limits)
        await self._account(result, c)
        return c

    # -- planning ------------------------------------------------------------------------
    async def _plan(
        self, request: str, intents: list[Intent], result: TurnResult, emit
    ) -> list[str]:
        if self.endpoint.is_rules:
            return self._rules_plan(intents)
        req = planner.plan_request(
            self.mode,
            self.gateway.catalog,
            self.locations(),
            request,
            intents,
            self.history[-HISTORY_TURNS:],
            self.narrow_tools,
        )
        ask = functools.partial(
            self._ask,
            schema=req.schema,
            result=result,
            emit=emit,
            kind="plan_token",
            grammar=req.grammar,
        )

        def review(cmd: str):
            return asyncio.to_thread(self._review, cmd)  # may read the robot's graph

        def gate_reason(commands: list[str]):
            return asyncio.to_thread(self._gate_reason, intents, commands)

        return await planner.plan(req, ask, review, gate_reason, result)

    # -- execution -----------------------------------------------------------------------
    async def _refuse(self, commands: list[str], reason: str, result: TurnResult, emit) -> None:
        """The gate's refusal: nothing runs, each command is recorded with the reason."""
        result.refused = reason
        for seq, cmd in enumerate(commands):
            checked = self._review(cmd).checked
            ex = Execution(
                cmd, checked.valid, f"refused by the intent gate: {reason}", checked.kind
            )
            result.commands.append(ex)
            await self.recorder.command(result, seq, ex)
            emit("command", ex)
        result.answer = f"I did not run this plan: {reason}. Nothing was sent to the robot."
        emit("answer_token", result.answer)

    async def _execute(self, commands: list[str], result: TurnResult, emit) -> None:
        for seq, cmd in enumerate(commands):
            ex = await asyncio.to_thread(
                self.gateway.run, cmd, self.confirm, review=self._reviews.get(cmd)
            )
            result.commands.append(ex)
            await self.recorder.command(result, seq, ex)
            emit("command", ex)
            if ex.executed and ex.kind == "actuate":
                self._reviews.clear()  # the robot changed (limits too): review what follows anew
            if not goals.started(ex):
                continue
            if seq + 1 < len(commands):
                emit("status", "waiting for the robot to arrive")
                outcome = await asyncio.to_thread(self.gateway.wait_until_idle, self.nav_wait_s)
                if outcome is None:  # a robot that reports none: its pose says
                    target = goals.target_of(ex, self.places())
                    outcome = await asyncio.to_thread(
                        goals.outcome_at, self.gateway, target, goals.goal_name(ex)
                    )
                result.waited[seq] = outcome
            else:
                result.started = await asyncio.to_thread(goals.started_text, self.gateway, ex)
                result.target = goals.target_of(ex, self.places())

    async def follow_up(self, result: TurnResult, timeout_s: float | None = None) -> str:
        """Wait for the goal the turn started to end; record and return how it ended."""
        wait = self.nav_wait_s if timeout_s is None else timeout_s
        result.outcome, text = await goals.follow(self.gateway, result.started, wait, result.target)
        await self.recorder.outcome(result)
        return text


def _check_mode(endpoint: LLMEndpoint, mode: str) -> None:
    if mode not in ("command", "tool") and not endpoint.is_rules:
        raise ValueError(f"mode must be 'command' or 'tool', not '{mode}'")


def _keep_partial(result: TurnResult, exc: LLMError) -> None:
    if exc.partial and f"{exc.partial} [cut off]" not in result.raw_replies:
        result.raw_replies.append(f"{exc.partial} [cut off]")
