"""The gateway's record of each command in the store (the commands table)."""

from __future__ import annotations

from collections.abc import Callable

from astiop.store import Store, StoreError
from astiop.transports.base import Execution


class CommandJournal:
    """One command's row in the store: written as sent before the robot is told, completed
    after; a command that never went out is written once, with why. `say_store_error`: where
    a row the store could not keep is said (the gateway says each reason once)."""

    UNFINISHED = "sent to the robot; astiop ended before it finished"

    def __init__(self, store: Store | None, say_store_error: Callable[[str], None], source: str):
        self.store = store
        self.say_store_error = say_store_error
        self.source = source
        self.row: int | None = None

    def sent(self, ex: Execution) -> None:
        store = self.store
        if store is None:
            return
        try:
            fields = {**ex.record(), "executed": 1, "reason": self.UNFINISHED}
            self.row = store.add_command(None, seq=0, source=self.source, **fields)
        except StoreError as exc:
            self._failed(ex, exc)

    def finish(self, ex: Execution) -> None:
        store = self.store
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
        self.say_store_error(note)
