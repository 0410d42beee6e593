"""The console as the approver of outside agents' actuations (astiop mcp): a heartbeat that says
a console is open on this database, and each pending request asked as the confirmation dialog
asks, y/n. No answer before the request's bound closes the dialog; the server refuses it."""

from __future__ import annotations

import contextlib
import sqlite3
import threading
import time

from astiop.screens.base import services_of
from astiop.screens.modals import ConfirmModal
from astiop.store import StoreError

POLL_S = 0.5


class ApprovalDesk(threading.Thread):
    def __init__(self, app):
        super().__init__(name="astiop-approvals", daemon=True)
        self.app = app
        self.halt = threading.Event()
        self._asked: set[int] = set()
        self._open: dict[int, ConfirmModal] = {}  # the UI thread's: dialogs still up

    def run(self) -> None:
        store = services_of(self.app).store
        try:
            while not self.halt.wait(POLL_S):
                try:
                    store.console_heartbeat()
                    pending = store.pending_approvals()
                except (StoreError, sqlite3.Error):
                    continue  # read-only, or busy: the server refuses what is not answered
                for request in pending:
                    if request["id"] not in self._asked:
                        self._asked.add(request["id"])
                        self.app.call_from_thread(self._ask, request)
                still = {request["id"] for request in pending}
                for gone in self._asked - still:  # answered in another console, or expired
                    self._asked.discard(gone)
                    self.app.call_from_thread(self._close, gone)
        finally:
            with contextlib.suppress(StoreError):
                store.console_closed()
            store.close()

    def _ask(self, request: dict) -> None:  # the UI thread
        left = max(0.0, request["expires_at"] - time.time())
        detail = f"\n{request['detail']}" if request["detail"] else ""
        robot = request.get("robot") or "the robot"  # a fleet's robot, by its name
        modal = ConfirmModal(
            f"{request['client']} (an outside agent, through MCP) asks to run a command that "
            f"moves {robot}:\n\n{request['command']}{detail}\n\n"
            f"Allow it? Without an answer in {left:.0f} s it is refused."
        )

        def done(ok: bool | None) -> None:
            self._open.pop(request["id"], None)
            if ok is None:
                return  # closed here because it was settled elsewhere
            self.app.run_worker(
                lambda: self._decide(request["id"], bool(ok)),
                thread=True,
                group="approvals",
                exit_on_error=False,
            )

        def expire() -> None:
            # too late: the server has refused it; dismiss() closes whatever is on top, so only
            # when this dialog is (one under another answers nothing that counts any more)
            if self.app.screen is modal:
                modal.dismiss(False)

        self._open[request["id"]] = modal
        self.app.push_screen(modal, done)
        self.app.set_timer(left, expire)

    def _close(self, approval_id: int) -> None:  # the UI thread
        """The request was settled elsewhere (another console, a tab, the server's bound): its
        dialog here answers nothing any more."""
        modal = self._open.pop(approval_id, None)
        if modal is None:
            return
        if self.app.screen is modal:
            modal.dismiss(None)
        self.app.notify(
            f"MCP request {approval_id} was settled elsewhere (another console or its time ran out)."
        )

    def _decide(self, approval_id: int, approved: bool) -> None:
        store = services_of(self.app).store
        try:
            if not store.decide_approval(approval_id, approved, "console"):
                return  # no longer pending: expired or answered elsewhere
        finally:
            store.close()  # this worker thread's connection
        word = "allowed" if approved else "refused"
        self.app.call_from_thread(self.app.notify, f"MCP request {approval_id} {word}.")
