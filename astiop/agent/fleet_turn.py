"""A turn in a fleet: the robot a request names is found without the model (fleet_words), the
request goes to that robot's own agent (its gateway, its places, its history), and the answer
says which robot it is about; a question about the whole fleet is answered from every robot's
reported state. A request that names no robot acts on the current one."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from astiop.agent.fleet_words import FleetWordsError, addressed, fleet_answer, fleet_question
from astiop.agent.models.specs import LLMEndpoint
from astiop.agent.recorder import Recorder
from astiop.agent.result import TurnResult
from astiop.agent.turn import Agent, OnEvent
from astiop.robot.fleet_watch import FleetRow
from astiop.store import Store


class FleetAgent:
    """`agent_for(name)`: that robot's Agent (made once); `current()`: the current robot's
    name; `rows()`: every robot's row; `places()`: the map's named places."""

    def __init__(
        self,
        agent_for: Callable[[str], Agent],
        current: Callable[[], str],
        rows: Callable[[], Sequence[FleetRow]],
        places: Callable[[], dict[str, tuple[float, float]]],
        store: Store | None = None,
        session: str = "",
    ):
        self.agent_for, self.current, self.rows, self.places = agent_for, current, rows, places
        self.recorder = Recorder(store, session)

    @property
    def agent(self) -> Agent:
        return self.agent_for(self.current())

    @property
    def mode(self) -> str:
        return self.agent.mode

    @property
    def model(self) -> str:
        return self.agent.model

    def switch(self, endpoint: LLMEndpoint | None = None, mode: str | None = None) -> None:
        for name in {r.name for r in self.rows()}:
            self.agent_for(name).switch(endpoint, mode)

    async def turn(self, request: str, on_event: OnEvent | None = None) -> TurnResult:
        rows = list(self.rows())
        kind = fleet_question(request)
        if kind is not None:
            return await self._said(request, fleet_answer(kind, rows))
        try:
            to = addressed(request, rows, self.places())
        except FleetWordsError as exc:
            return await self._said(request, f"{exc}.")
        name = to.name if to else self.current()
        said = to.request if to else request
        emit = on_event or (lambda kind, data: None)
        emit("status", f"to {name} ({to.how})" if to else f"to {name} (the current robot)")
        try:
            agent = self.agent_for(name)
        except LookupError as exc:  # not reached: said, never guessed at
            return await self._said(request, f"{exc}.")
        result = await agent.turn(said, on_event)
        result.robot = name
        if result.answer and not result.answer.startswith(f"{name}:"):
            result.answer = f"{name}: {result.answer}"
        return result

    async def follow_up(self, result: TurnResult, timeout_s: float | None = None) -> str:
        return await self.agent_for(result.robot or self.current()).follow_up(result, timeout_s)

    async def _said(self, request: str, answer: str) -> TurnResult:
        """An answer given from the fleet's rows alone (no model, no command)."""
        t0 = time.perf_counter()
        result = TurnResult("fleet", "rules", request, answer=answer, grounding="rules")
        await self.recorder.start(result)
        result.total_s = time.perf_counter() - t0
        await self.recorder.finish(result)
        return result
