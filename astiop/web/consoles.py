"""The console processes behind the tabs: one per browser connection, started with an argument
list (no shell), in a process group of its own so that closing its tab ends it and everything it
started (the embedded model's server included)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import shlex
import signal

from textual_serve.app_service import AppService

log = logging.getLogger("astiop.serve")
QUIT_S = 5.0  # for a console to quit when its tab closes, before it is terminated
TERM_S = 3.0  # then for SIGTERM, before SIGKILL


class ConsoleProcess(AppService):
    """textual-serve's process protocol (stdin packets, stdout frames) on `argv`, not a shell
    line: the console's arguments are never re-parsed by a shell."""

    def __init__(self, argv: list[str], env: dict[str, str], **kwargs):
        super().__init__(shlex.join(argv), **kwargs)
        self.argv = argv
        self.extra_env = env
        self.pid: int | None = None

    def _build_environment(self, width: int = 80, height: int = 24) -> dict[str, str]:
        environment = super()._build_environment(width, height)
        environment.update(self.extra_env)
        return environment

    async def _open_app_process(self, width: int = 80, height: int = 24):
        self._process = process = await asyncio.create_subprocess_exec(
            *self.argv,
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
            env=self._build_environment(width=width, height=height),
            start_new_session=True,
        )
        self._stdin = process.stdin
        self.pid = process.pid
        return process

    async def end(self) -> None:
        """Ask the console to quit; terminate it if it does not, then its whole group."""
        try:
            await asyncio.wait_for(self.stop(), QUIT_S)
        except (asyncio.TimeoutError, ConnectionError, RuntimeError):
            log.warning("console %s did not quit in %.0f s: terminating it", self.pid, QUIT_S)
        process = self._process
        if process is None:
            return
        if process.returncode is None:
            self._signal_group(signal.SIGTERM)
            try:
                await asyncio.wait_for(process.wait(), TERM_S)
            except asyncio.TimeoutError:
                self._signal_group(signal.SIGKILL)
                await process.wait()
        # what the console started and left behind (its group outlives it)
        self._signal_group(signal.SIGTERM)
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task

    def _signal_group(self, sig: int) -> None:
        if self.pid is not None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.pid, sig)
