"""The MCP calls' record in the store (the audit trail): each call as an interaction, each command
it sent, how it ended. The robot is still served when the store cannot write (a read-only or
broken database), but a failed write is never silent: the call's answer says it, and the
operator reads it once on the server's stderr."""

from __future__ import annotations

import contextvars
import sys
import threading
import time
from dataclasses import dataclass, field

from astiop.bounded import MAX_REPLY_CHARS, one_line
from astiop.store import Store, StoreError
from astiop.transports.base import Execution

MAX_SAID = 64  # distinct failures said on stderr; past that, a broken store would flood it


@dataclass
class Call:
    """The tool call being served: who asked, and its interaction in the store."""

    client: str
    what: str
    interaction_id: int | None = None
    seq: int = 0
    unrecorded: list[str] = field(default_factory=list)  # what the store failed to keep

    def note(self) -> str:
        """The line the answer carries when the record is incomplete ('' when it is whole)."""
        if not self.unrecorded:
            return ""
        return one_line("note: not in astiop's audit trail: " + "; ".join(self.unrecorded), 500)


CALL: contextvars.ContextVar[Call] = contextvars.ContextVar("mcp_call")


class AuditTrail:
    def __init__(self, store: Store):
        self.store = store
        self._said: set[str] = set()
        self._lock = threading.Lock()

    def start(self, call: Call) -> None:
        try:
            call.interaction_id = self.store.start_interaction(
                model=f"mcp:{call.client}", mode="mcp", prompt=call.what, session="mcp"
            )
        except StoreError as exc:
            self._failed(call, "the call", exc)

    def command(self, ex: Execution) -> None:
        call = CALL.get(None)
        if call is None or call.interaction_id is None:
            return  # not inside a recorded call (its start failed, and said so)
        call.seq += 1
        try:
            self.store.add_command(call.interaction_id, seq=call.seq, source="mcp", **ex.record())
        except StoreError as exc:
            self._failed(call, f"the command {one_line(ex.command, 120)!r}", exc)

    def finish(self, call: Call, answer: str, t0: float, error: bool) -> None:
        if call.interaction_id is None:
            return
        fields = {
            "finished_at": time.time(),
            "answer": answer[:MAX_REPLY_CHARS],
            "total_s": time.perf_counter() - t0,
            "status": "error" if error else "done",
            "error": answer if error else None,
        }
        try:
            self.store.update_interaction(call.interaction_id, **fields)
        except StoreError as exc:
            self._failed(call, "the call's answer", exc)

    def outcome(self, call: Call, outcome: str) -> None:
        """A followed goal's end, after the call has answered: only stderr can say it then."""
        if call.interaction_id is None:
            return
        try:
            self.store.update_interaction(
                call.interaction_id, outcome=outcome, outcome_at=time.time()
            )
        except StoreError as exc:
            self._failed(call, f"the goal's outcome ({outcome})", exc)

    def _failed(self, call: Call, what: str, exc: StoreError) -> None:
        reason = one_line(exc, 300)
        call.unrecorded.append(f"{what} was not recorded: {reason}")
        with self._lock:
            if reason in self._said or len(self._said) >= MAX_SAID:
                return
            self._said.add(reason)
        line = f"astiop mcp: the audit trail could not record {what}: {reason}"
        print(line, file=sys.stderr, flush=True)
