"""The gateway's record of each command in the store (the commands table)."""

from __future__ import annotations

from typing import Protocol

from astiop.store import Store, StoreError
from astiop.transports.base import Execution


class Journaled(Protocol):
    """What a `CommandJournal` needs of its gateway."""

    store: Store | None

    def _say_store_error(self, message: str) -> None: ...


class CommandJournal:
    """One command's row in the store: written as sent before the robot is told, completed
    after; a command that never went out is written once, with why."""

    UNFINISHED = "sent to the robot; astiop ended before it finished"

    def __init__(self, gateway: Journaled, source: str):
        self.gateway = gateway
        self.source = source
        self.row: int | None = None

    def sent(self, ex: Execution) -> None:
        store = self.gateway.store
        if store is None:
            return
        try:
            fields = {**ex.record(), "executed": 1, "reason": self.UNFINISHED}
            self.row = store.add_command(None, seq=0, source=self.source, **fields)
        except StoreError as exc:
            self._failed(ex, exc)

    def finish(self, ex: Execution) -> None:
        store = self.gateway.store
        if store is None:
            return
        try:
            if self.row is None:
                store.add_command(None, seq=0, source=self.source, **ex.record())
            else:
                store.finish_command(self.row, **ex.record())
        except StoreError as exc:
            self._failed(ex, exc)

    def _failed(self, ex: Execution, exc: StoreError) -> None:
        note = f"not in astiop's record of commands: {exc}"
        if note not in ex.notes:
            ex.notes.append(note)
        self.gateway._say_store_error(note)
