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


async def _nowhere(*_args) -> None:
    """A spare console's output before it has a tab (it writes nothing until then)."""


class ConsoleProcess(AppService):
    """textual-serve's process protocol (stdin packets, stdout frames) on `argv`, not a shell
    line: the console's arguments are never re-parsed by a shell.

    A spare is started before any tab asks for it: its imports (~1.2 s of a console's ~2 s
    start) are done when a tab comes, and it costs no CPU while it waits (blocked on stdin)."""

    def __init__(self, argv: list[str], env: dict[str, str], download_manager, spare=False):
        super().__init__(
            shlex.join(argv),
            write_bytes=_nowhere,
            write_str=_nowhere,
            close=_nowhere,
            download_manager=download_manager,
        )
        self.argv = argv
        self.extra_env = {**env, "ASTIOP_CONSOLE_SPARE": "1"} if spare else env
        self.spare = spare
        self.pid: int | None = None
        self._starting: asyncio.Future | None = None

    def begin(self, width: int = 80, height: int = 24) -> None:
        """Start the process without waiting for it (a spare, while the server goes on)."""
        self._starting = asyncio.ensure_future(self.start(width, height))

    async def ready(self) -> bool:
        """Started and still running."""
        if self._starting is not None:
            with contextlib.suppress(Exception):
                await self._starting
        return self.alive

    @property
    def alive(self) -> bool:
        return self._process is not None and self._process.returncode is None

    async def attach(self, write_bytes, write_str, close, width: int, height: int) -> None:
        """Give the console its tab: its output goes there from now on."""
        self.remote_write_bytes, self.remote_write_str, self.remote_close = (
            write_bytes,
            write_str,
            close,
        )
        if self.spare:
            self.stdin.write(f"go {width} {height}\n".encode())
            await self.stdin.drain()
            self.spare = False

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

    async def run(self) -> None:
        """textual-serve's reading of the console's output; when the console's process ends on
        its own (a crash, a signal: no "exit" message), the tab is told and the end is said."""
        await super().run()
        process = self._process
        if process is None or self.spare:
            return
        code = await process.wait()
        if code != 0:
            how = f"signal {-code}" if code < 0 else f"exit status {code}"
            log.error("console %s ended on its own (%s)", self.pid, how)
        with contextlib.suppress(Exception):
            await self.remote_close()

    async def end(self) -> None:
        """Ask the console to quit; terminate it if it does not, then its whole group."""
        await self.ready()
        try:
            if self.spare and self._stdin is not None:
                if self._task is not None:  # it never had a tab: nothing to read from it
                    self._task.cancel()
                self._stdin.close()  # a spare waits for its tab: end of input ends it
                await asyncio.wait_for(self._process.wait(), QUIT_S)
            else:
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
