"""The web server of `astiop serve` (aiohttp): the log-in, the console page, a console process per
websocket, and the page's E-STOP button. Nothing reaches a console before its token is checked."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web
from textual_serve.download_manager import DownloadManager

from astiop.web.access import (
    COOKIE,
    Access,
    Network,
    client_address,
    host_name,
    loopback_host,
)
from astiop.web.consoles import ConsoleProcess
from astiop.web.pages import console_page, login_page
from astiop.web.store_reads import StoreReads

log = logging.getLogger("astiop.serve")
ESTOP_S = 60.0  # for `astiop estop` to reach the robot (its own timeouts are shorter)
RECORD_S = 2.0  # the button's answer waits this long at most for the database's latch
MAX_MESSAGE = 64 * 1024  # a browser's keystrokes and resizes are small
STATIC = Path(str(files("textual_serve") / "static"))


@dataclass
class ServeConfig:
    host: str
    port: int
    token: str | None
    console_argv: list[str]  # one console (the web driver is set in its environment)
    estop_argv: list[str]  # `astiop ... estop` on the same settings
    db: Path
    robot: str  # said in the page's title and header
    console_env: dict[str, str] = field(default_factory=dict)
    max_consoles: int = 4  # benchmarks/serve_memory.py: ~430 MiB RSS a tab (embedded model)
    # the robot stopped from this process (who pressed it -> failures), where it can be:
    # the button never waits for a new process
    stop_robot: Callable[[str], list[str]] | None = None
    warm: bool = True  # a console started ahead, waiting for the next tab
    trusted_proxies: tuple[Network, ...] = ()  # whose X-Forwarded-For names the client


class WebServer:
    def __init__(self, config: ServeConfig):
        self.config = config
        self.access = Access(config.token)
        self.consoles: set[ConsoleProcess] = set()
        self.downloads = DownloadManager()
        self.reads = StoreReads(config.db)
        self._estop_lock = asyncio.Lock()
        self._stopper = ThreadPoolExecutor(1, thread_name_prefix="astiop-serve-estop")
        self.spare: ConsoleProcess | None = None
        self.opening = 0  # tabs given a console, from before it starts to after it ends

    # --- who may ------------------------------------------------------------------------------

    def _address(self, request: web.Request) -> str:
        forwarded = request.headers.getall("X-Forwarded-For", [])
        return client_address(request.remote, forwarded, self.config.trusted_proxies)

    def _same_origin(self, request: web.Request) -> bool:
        """A browser says which page asked; only this server's pages may act (a page elsewhere
        cannot open a console or stop the robot through the operator's browser)."""
        origin = request.headers.get("Origin")
        if origin is None:
            return True  # not a browser's cross-site request
        hosts = {request.headers.get("Host"), request.headers.get("X-Forwarded-Host")}
        return urlsplit(origin).netloc in hosts - {None}

    def _allowed(self, request: web.Request) -> bool:
        if not self._same_origin(request):
            return False
        if self.config.token is None and not loopback_host(host_name(request.host)):
            return False  # no token: a page on another name (DNS rebinding) is not ours
        return self.access.admitted(request.cookies.get(COOKIE))

    def _secure(self, request: web.Request) -> bool:
        return request.secure or request.headers.get("X-Forwarded-Proto", "") == "https"

    async def _token_given(self, request: web.Request, token: str) -> web.Response:
        address = self._address(request)
        # the right token first: a guesser's penalty on the same address never holds it back
        if not self.access.token_matches(token):
            wait = self.access.wrong_try(address)  # counted before anything awaits
            if wait is None:
                log.warning("wrong token from %s: refused at once (too many waiting)", address)
                return web.Response(
                    status=429,
                    text=f"Too many wrong tokens from {address}: try again in a minute.",
                    headers={"Retry-After": "60"},
                )
            log.warning("wrong token from %s (answered in %.0f s)", address, wait)
            await asyncio.sleep(wait)  # its turn, after this address's earlier wrong tries
            return web.Response(
                status=401, text=login_page(self.config.robot, wrong=True), content_type="text/html"
            )
        self.access.right_token(address)
        response = web.Response(status=302, headers={"Location": "./"})
        response.set_cookie(
            COOKIE,
            self.access.open_session(),
            httponly=True,
            samesite="Strict",
            secure=self._secure(request),
            path="/",
        )
        return response

    # --- pages --------------------------------------------------------------------------------

    async def index(self, request: web.Request) -> web.StreamResponse:
        token = request.query.get("token")
        if token is not None and self.config.token is not None:
            return await self._token_given(request, token)  # a link with the token: a cookie
        if not self._allowed(request):
            if self.config.token is None:
                raise web.HTTPForbidden(text="astiop serve answers only on this machine's names")
            raise web.HTTPFound("login")
        font = request.query.get("fontsize", "16")
        size = int(font) if font.isdigit() and 6 <= int(font) <= 48 else 16
        page = console_page(self.config.robot, "static/", size)
        return web.Response(text=page, content_type="text/html", headers=_NO_STORE)

    async def login_form(self, request: web.Request) -> web.Response:
        if self.config.token is None:
            raise web.HTTPFound("./")
        return web.Response(
            text=login_page(self.config.robot, wrong=False), content_type="text/html"
        )

    async def login(self, request: web.Request) -> web.Response:
        if self.config.token is None:
            raise web.HTTPFound("./")
        if not self._same_origin(request):
            raise web.HTTPForbidden(text="not from this server's page")
        try:
            form = await request.post()
        except ValueError:  # not a form a browser sends (the size is capped by aiohttp: 413)
            raise web.HTTPBadRequest(text="not a log-in form") from None
        token = form.get("token")
        return await self._token_given(request, token if isinstance(token, str) else "")

    # --- the E-STOP button --------------------------------------------------------------------

    async def estop_state(self, request: web.Request) -> web.Response:
        if not self._allowed(request):
            raise web.HTTPUnauthorized(text="log in first")
        latch = await self.reads.latch()
        return web.json_response(_latch_said(latch), headers=_NO_STORE)

    async def alerts(self, request: web.Request) -> web.Response:
        """The bell: the open alerts, read by the page every half second."""
        if not self._allowed(request):
            raise web.HTTPUnauthorized(text="log in first")
        return web.json_response(await self.reads.alerts(), headers=_NO_STORE)

    async def estop(self, request: web.Request) -> web.Response:
        # a custom header: a page elsewhere cannot send it without this server's consent (CORS)
        if not self._allowed(request) or request.headers.get("X-Astiop") != "estop":
            raise web.HTTPForbidden(text="not from this server's page")
        who = f"serve: browser at {self._address(request)}"
        started = time.monotonic()
        stopped = None
        if self.config.stop_robot is not None:  # the robot first, from this process, at once
            stopped = asyncio.get_running_loop().run_in_executor(
                self._stopper, self.config.stop_robot, who
            )
        try:  # then every process on this database; a database in trouble never holds it up
            latch = await asyncio.wait_for(self.reads.latch(who), RECORD_S)
            recorded = ""
        except asyncio.TimeoutError:
            latch, recorded = {}, f"not latched in the database within {RECORD_S:g} s"
        except Exception as exc:  # noqa: BLE001 - full, damaged, locked, read-only
            latch, recorded = {}, f"not latched in the database: {exc}"
        latched_ms = (time.monotonic() - started) * 1000
        if stopped is not None:
            failures = await stopped
            ok, said = not failures, "; ".join(failures) or "the robot was told to stop"
        else:
            async with self._estop_lock:  # one `astiop estop` at a time
                ok, said = await self._stop_robot()
        if recorded:
            said += f" ({recorded})"
        log.warning(
            "E-STOP from %s: %s; %s", who, recorded or f"latched in {latched_ms:.0f} ms", said
        )
        body = _latch_said(latch) if latch else {"engaged": True}
        body.update(ok=ok, robot=said, latched_ms=round(latched_ms, 1), recorded=not recorded)
        body["message"] = ("E-STOP ENGAGED: " if ok else "E-STOP, robot not reached: ") + said
        return web.json_response(body, status=200 if ok else 502)

    async def _stop_robot(self) -> tuple[bool, str]:
        process = await asyncio.create_subprocess_exec(
            *self.config.estop_argv,
            env={**os.environ, **self.config.console_env},
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
        )
        try:
            out, _ = await asyncio.wait_for(process.communicate(), ESTOP_S)
        except asyncio.TimeoutError:
            process.kill()
            await process.wait()
            return False, f"`astiop estop` did not finish in {ESTOP_S:.0f} s"
        lines = [line for line in out.decode("utf-8", "replace").splitlines() if line.strip()]
        return process.returncode == 0, (lines[-1] if lines else f"exit {process.returncode}")

    # --- the consoles -------------------------------------------------------------------------

    async def websocket(self, request: web.Request) -> web.StreamResponse:
        if not self._allowed(request):
            raise web.HTTPForbidden(text="log in first")  # refused before any process starts
        if self.opening >= self.config.max_consoles:
            return await self._refuse(request)
        self.opening += 1  # taken before any await: a burst of tabs cannot all pass the check
        freed = False

        def free() -> None:  # once, as soon as the console has ended (before its socket closes)
            nonlocal freed
            if not freed:
                freed = True
                self.opening -= 1

        try:
            return await self._console_for(request, free)
        finally:
            free()

    async def _refuse(self, request: web.Request) -> web.StreamResponse:
        """A tab over the limit: told so in one line on its terminal, then closed."""
        said = (
            f"astiop serve: {self.opening} consoles are open, the most this server allows "
            f"(--max-consoles {self.config.max_consoles}): close a tab, then reload this page."
        )
        log.warning("console refused to %s: %d open", self._address(request), self.opening)
        socket = web.WebSocketResponse(max_msg_size=MAX_MESSAGE)
        await socket.prepare(request)
        with contextlib.suppress(Exception):
            await socket.send_bytes(f"\r\n{said}\r\n".encode())
            await socket.close(code=1013, message=said[:120].encode())  # 1013: try again later
        return socket

    async def _console_for(
        self, request: web.Request, free: Callable[[], None]
    ) -> web.StreamResponse:
        socket = web.WebSocketResponse(heartbeat=15, max_msg_size=MAX_MESSAGE)
        await socket.prepare(request)
        width = _bounded_int(request.query.get("width"), 80, 20, 500)
        height = _bounded_int(request.query.get("height"), 24, 8, 200)
        console, self.spare = self.spare, None
        self._warm_next()
        if console is not None and not await console.ready():
            await console.end()  # a spare that failed: its error is in the server's log
            console = None
        self.consoles.add(console := console or self._console())
        try:
            if not console.alive:
                await console.start(width, height)
            await console.attach(socket.send_bytes, socket.send_str, socket.close, width, height)
            log.info(
                "console %s opened for %s (%d open)",
                console.pid,
                self._address(request),
                len(self.consoles),
            )
            await _relay(socket, console)
        except asyncio.CancelledError:
            pass
        finally:
            await console.end()
            self.consoles.discard(console)
            free()
            log.info("console %s ended (%d open)", console.pid, self.opening)
            with contextlib.suppress(Exception):
                await socket.close()
        return socket

    def _console(self, spare: bool = False) -> ConsoleProcess:
        return ConsoleProcess(
            self.config.console_argv, self.config.console_env, self.downloads, spare=spare
        )

    def _warm_next(self) -> None:
        """Start the spare the next tab will take (none with --no-warm)."""
        if self.config.warm and self.spare is None:
            self.spare = self._console(spare=True)
            self.spare.begin()

    async def started(self, _app: web.Application) -> None:
        self._warm_next()

    async def end_all(self, _app: web.Application | None = None) -> None:
        ending = list(self.consoles) + ([self.spare] if self.spare is not None else [])
        self.spare = None
        await asyncio.gather(*(console.end() for console in ending))
        self.reads.close()


_NO_STORE = {"Cache-Control": "no-store"}


def _latch_said(latch: dict) -> dict:
    if not latch:
        return {"engaged": False, "message": "E-STOP released"}
    at = time.strftime("%H:%M:%S", time.localtime(latch["at"])) if latch.get("at") else "?"
    return {
        "engaged": True,
        "by": latch.get("by"),
        "at": latch.get("at"),
        "message": f"E-STOP ENGAGED by {latch.get('by')} at {at}",
    }


def _bounded_int(value: str | None, default: int, low: int, high: int) -> int:
    return min(high, max(low, int(value))) if value and value.isdigit() else default


async def _relay(socket: web.WebSocketResponse, console: ConsoleProcess) -> None:
    """The browser's keys, size and focus to the console, until the tab goes."""
    async for message in socket:
        if message.type != WSMsgType.TEXT:
            continue
        try:
            envelope = json.loads(message.data)
            kind, data = (envelope + [None])[:2] if isinstance(envelope, list) else (None, None)
        except (ValueError, TypeError):
            continue  # not what a page of ours sends: ignored
        if kind == "stdin" and isinstance(data, str):
            await console.send_bytes(data.encode("utf-8"))
        elif kind == "resize" and isinstance(data, dict):
            width = _bounded_int(str(data.get("width", "")), 80, 20, 500)
            height = _bounded_int(str(data.get("height", "")), 24, 8, 200)
            await console.set_terminal_size(width, height)
        elif kind == "ping" and isinstance(data, str):
            await socket.send_json(["pong", data[:64]])
        elif kind == "blur":
            await console.blur()
        elif kind == "focus":
            await console.focus()


def make_web_app(config: ServeConfig) -> tuple[web.Application, WebServer]:
    server = WebServer(config)
    app = web.Application(client_max_size=MAX_MESSAGE)
    app.add_routes(
        [
            web.get("/", server.index),
            web.get("/login", server.login_form),
            web.post("/login", server.login),
            web.get("/ws", server.websocket),
            web.get("/estop", server.estop_state),
            web.get("/alerts", server.alerts),
            web.post("/estop", server.estop),
            web.static("/static", STATIC),
        ]
    )
    app.on_startup.append(server.started)
    app.on_shutdown.append(server.end_all)
    return app, server


async def serve_until_stopped(config: ServeConfig, ready) -> None:
    """Serve until SIGINT or SIGTERM; `ready(url)` once the port is open (OSError if it cannot
    be)."""
    app, _server = make_web_app(config)
    runner = web.AppRunner(app, handle_signals=False, access_log=None)
    await runner.setup()
    try:
        site = web.TCPSite(runner, config.host, config.port)
        await site.start()
        ready(f"http://{_url_host(config.host)}:{config.port}/")
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        await stop.wait()
    finally:
        await runner.cleanup()


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host
