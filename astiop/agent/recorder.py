"""Writes one agent turn to the store as it happens: off the event loop, in order.

A write waits for SQLite (up to its busy timeout) in a worker thread, so the console keeps
drawing while another process holds the database.
"""

from __future__ import annotations

import asyncio
import time

from astiop.agent.result import TurnResult
from astiop.store import Store
from astiop.transports.base import Execution


class Recorder:
    def __init__(self, store: Store | None, session: str = ""):
        self.store = store
        self.session = session

    async def start(self, result: TurnResult) -> None:
        if self.store is not None:
            result.interaction_id = await asyncio.to_thread(
                self.store.start_interaction,
                model=result.model,
                mode=result.mode,
                prompt=result.prompt,
                session=self.session,
                robot=result.robot,
            )

    async def replies(self, result: TurnResult) -> None:
        """The raw replies so far: kept even if the turn dies next."""
        if self.store is not None and result.interaction_id:
            await asyncio.to_thread(
                self.store.update_interaction,
                result.interaction_id,
                raw_replies=list(result.raw_replies),
            )

    async def command(self, result: TurnResult, seq: int, ex: Execution) -> None:
        if self.store is not None and result.interaction_id:
            await asyncio.to_thread(self._command, result.interaction_id, seq, ex)

    def _command(self, interaction_id: int, seq: int, ex: Execution) -> None:
        assert self.store is not None
        self.store.add_command(interaction_id, seq=seq, source="chat", **ex.record())

    async def finish(self, result: TurnResult, status: str | None = None) -> None:
        await asyncio.to_thread(self.finish_now, result, status)

    def finish_now(self, result: TurnResult, status: str | None = None) -> None:
        """Synchronous, for a turn being canceled (no more awaiting then)."""
        if self.store is None or not result.interaction_id:
            return
        self.store.update_interaction(
            result.interaction_id,
            finished_at=time.time(),
            answer=result.answer,
            model_answer=result.model_answer or None,
            grounding=result.grounding or None,
            raw_replies=result.raw_replies,
            ttft_s=result.ttft_s,
            total_s=result.total_s,
            llm_s=result.llm_s,
            prompt_tokens=result.prompt_tokens,
            completion_tokens=result.completion_tokens,
            error=result.error or None,
            status=status or ("error" if result.error else "done"),
        )

    async def outcome(self, result: TurnResult) -> None:
        if self.store is not None and result.interaction_id:
            await asyncio.to_thread(
                self.store.update_interaction,
                result.interaction_id,
                outcome=result.outcome,
                outcome_at=time.time(),
            )
