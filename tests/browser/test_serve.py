"""`astiop serve` as a browser meets it, without the browser: a console per websocket and none
without the token, the page's origin checked, the E-STOP button, every process gone with its tab.
(tests/browser/test_serve_browser.py drives the same server from headless Chromium.)"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import re
import time
from pathlib import Path

import aiohttp
import pytest

from astiop.store import Store
from astiop.watches.model import Watch
from astiop.web.access import (
    FREE_TRIES,
    Access,
    client_address,
    host_name,
    loopback_host,
    proxy_networks,
)
from tests.cli_runner import run_cli
from tests.ros import require_ros, ros_client
from tests.web_console import (
    ENV,
    Terminal,
    consoles_of,
    descendants,
    free_port,
    start_serve,
    stop_serve,
    wait_until,
)

TOKEN = "serve-token-0123456789abcdef"


async def read_until(ws, terminal: Terminal, pattern: str, timeout: float = 30.0) -> None:
    """Feed the console's frames to `terminal` until its screen matches."""
    deadline = time.monotonic() + timeout
    while not terminal.has(pattern):
        left = deadline - time.monotonic()
        assert left > 0, f"{pattern!r} never shown:\n{terminal.text()}"
        try:
            message = await ws.receive(timeout=left)
        except asyncio.TimeoutError:
            continue
        if message.type == aiohttp.WSMsgType.BINARY:
            terminal.feed(message.data)
        elif message.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED):
            raise AssertionError(f"the console closed:\n{terminal.text()}")


async def _pump(ws, terminal: Terminal) -> None:
    """A tab's frames read as a browser reads them, all along: the server's heartbeat pings are
    answered as they come (aiohttp answers them as it receives; a tab left unread for 15 s on a
    loaded machine was closed by its heartbeat)."""
    while True:
        message = await ws.receive()
        if message.type == aiohttp.WSMsgType.BINARY:
            terminal.feed(message.data)
        elif message.type in (
            aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR
        ):  # fmt: skip
            terminal.closed = True
            return


async def _shown(terminal: Terminal, pattern: str, timeout: float = 30.0) -> None:
    """Until the screen a `_pump` feeds matches."""
    deadline = time.monotonic() + timeout
    while not terminal.has(pattern):
        assert not terminal.closed, f"the console closed:\n{terminal.text()}"
        assert time.monotonic() < deadline, f"{pattern!r} never shown:\n{terminal.text()}"
        await asyncio.sleep(0.05)


def test_access_slows_wrong_tokens_in_turn_and_forgets_them():
    now = [0.0]
    access = Access(TOKEN, clock=lambda: now[0])
    waits = [access.wrong_try("10.0.0.9") for _ in range(FREE_TRIES + 6)]  # all at once
    # each waits its turn after the ones before: 0, 0, 0, then +1, +2, +4, +8 s; past 30 s away,
    # refused at once
    assert waits == [0.0, 0.0, 0.0, 1.0, 3.0, 7.0, 15.0, None, None]
    assert access.wrong_try("10.0.0.10") == 0.0, "another address is not slowed"
    now[0] += 15
    assert access.wrong_try("10.0.0.9") == 30.0, "one at a time, at most 30 s apart"
    for _ in range(5000):  # a flood never overflows (2.0 ** 1027 did) nor waits past 30 s
        assert access.wrong_try("10.0.0.9") in (None, 30.0)
    assert access.wrong_try("2001:db8::1") == 0.0
    assert [access.wrong_try("2001:db8::2") for _ in range(3)] == [0.0, 0.0, 1.0], "per /64"
    now[0] += 10_000
    assert access.wrong_try("10.0.0.9") == 0.0, "forgotten after ten quiet minutes"
    session = access.open_session()
    assert access.admitted(session) and not access.admitted("guess") and not access.admitted(None)
    now[0] += 13 * 3600
    assert not access.admitted(session), "a session ends"
    assert not access.token_matches(TOKEN + "x") and access.token_matches(TOKEN)


def test_the_client_is_named_by_a_trusted_proxy_only():
    proxy = proxy_networks(["127.0.0.1", "10.1.0.0/16"])
    assert client_address("127.0.0.1", ["198.51.100.7"], proxy) == "198.51.100.7"
    assert client_address("127.0.0.1", ["1.2.3.4, 198.51.100.7"], proxy) == "198.51.100.7", (
        "what the client wrote left of its own address is not believed"
    )
    assert client_address("127.0.0.1", ["198.51.100.7, 10.1.2.3"], proxy) == "198.51.100.7"
    assert client_address("192.0.2.1", ["198.51.100.7"], proxy) == "192.0.2.1", "not a proxy"
    assert client_address("127.0.0.1", ["198.51.100.7"], ()) == "127.0.0.1", "none configured"
    assert client_address("127.0.0.1", ["junk"], proxy) == "127.0.0.1"


def test_loopback_names():
    assert [loopback_host(host_name(h)) for h in ("localhost:8765", "127.0.0.1:1", "[::1]:80")] == [
        True,
        True,
        True,
    ]
    assert not loopback_host(host_name("evil.example:8765"))
    assert not loopback_host(host_name("192.168.1.20:8765"))


@pytest.mark.slow
async def test_each_websocket_is_a_console_and_closing_it_ends_the_process(tmp_path):
    port = free_port()
    server = start_serve(tmp_path / "a.db", port, "--no-warm")
    url = f"http://127.0.0.1:{port}"
    try:
        async with aiohttp.ClientSession() as http:
            async with http.get(url + "/") as page:
                assert page.status == 200
                assert "<title>astiop: simulator (one per tab)</title>" in await page.text()
            assert consoles_of(server.pid) == [], "a page alone starts nothing"
            first = await http.ws_connect(url + "/ws?width=120&height=40")
            second = await http.ws_connect(url + "/ws?width=120&height=40")
            one, two = Terminal(), Terminal()
            await read_until(first, one, r"battery\s+\S+\s+\d+\.\d %")
            await read_until(second, two, r"battery\s+\S+\s+\d+\.\d %")
            assert len(consoles_of(server.pid)) == 2, "one console per tab"
            await first.close()
            wait_until(lambda: len(consoles_of(server.pid)) == 1, what="the first console to end")
            await second.close()
            wait_until(lambda: descendants(server.pid) == [], what="every process to end")
    finally:
        log = stop_serve(server)
    assert "console" in log and "ended (0 open)" in log, log


@pytest.mark.slow
async def test_without_the_token_nothing_starts_and_with_it_a_console_does(tmp_path):
    port = free_port()
    server = start_serve(
        tmp_path / "a.db", port, "--no-warm", env={**ENV, "ASTIOP_SERVE_TOKEN": TOKEN}
    )
    url = f"http://127.0.0.1:{port}"
    try:
        assert TOKEN.encode() not in Path(f"/proc/{server.pid}/cmdline").read_bytes()  # `ps`
        # unsafe: aiohttp's jar keeps no cookie of an IP address unless asked (a browser does)
        async with aiohttp.ClientSession(cookie_jar=aiohttp.CookieJar(unsafe=True)) as http:
            async with http.get(url + "/", allow_redirects=False) as page:
                assert (page.status, page.headers["Location"]) == (302, "login")
            async with http.get(url + "/ws") as refused:
                assert refused.status == 403
            async with http.get(url + "/estop") as refused:
                assert refused.status == 401
            started = time.monotonic()
            for _ in range(FREE_TRIES + 1):  # the last of these waits 1 s
                async with http.post(url + "/login", data={"token": "wrong-token-000000"}) as r:
                    assert r.status == 401 and "Wrong token" in await r.text()
            assert time.monotonic() - started >= 1.0, "repeated wrong tokens slow down"
            assert descendants(server.pid) == [], "a wrong token starts no process"
            async with http.post(url + "/login", data={"token": TOKEN}, allow_redirects=False) as r:
                assert r.status == 302 and "astiop_session" in r.cookies
                assert "HttpOnly" in r.headers["Set-Cookie"]
            ws = await http.ws_connect(url + "/ws")
            await read_until(ws, Terminal(), r"Dashboard")
            console = consoles_of(server.pid)
            assert len(console) == 1
            environ = Path(f"/proc/{console[0]}/environ").read_bytes()
            assert TOKEN.encode() not in environ, "the token is not handed to a console"
            await ws.close()
        async with (  # a link with the token: a cookie
            aiohttp.ClientSession() as link,
            link.get(url + f"/?token={TOKEN}", allow_redirects=False) as r,
        ):
            assert r.status == 302 and "astiop_session" in r.cookies
    finally:
        stop_serve(server)


STORM = 2000


@pytest.mark.slow
async def test_a_storm_of_wrong_tokens_locks_out_no_operator(tmp_path):
    """2,000 wrong tokens at once from one client behind the trusted proxy: each is counted and
    answered in its turn or refused at once, never a 500, each logged with its address; the right
    token gets in meanwhile, from another client and from the guesser's own address."""
    port = free_port()
    env = {**ENV, "ASTIOP_SERVE_TOKEN": TOKEN, "ASTIOP_SERVE__TRUSTED_PROXIES": "127.0.0.1"}
    server = start_serve(tmp_path / "a.db", port, "--no-warm", env=env)
    url = f"http://127.0.0.1:{port}/login"
    guesser = {"X-Forwarded-For": "6.6.6.6, 203.0.113.5"}  # the proxy appended the real one

    async def login(http, token: str, headers: dict) -> int:
        async with http.post(
            url, data={"token": token}, headers=headers, allow_redirects=False
        ) as r:
            return r.status

    try:
        connector = aiohttp.TCPConnector(limit=0)
        async with aiohttp.ClientSession(connector=connector) as http:
            storm = [
                asyncio.ensure_future(login(http, f"wrong-token-{i:06d}", guesser))
                for i in range(STORM)
            ]
            log = server.log_path
            while "refused at once" not in log.read_text():  # the storm has filled its turns
                assert not all(task.done() for task in storm), log.read_text()[-2000:]
                await asyncio.sleep(0.1)
            async with aiohttp.ClientSession() as operator:
                assert await login(operator, TOKEN, {"X-Forwarded-For": "203.0.113.9"}) == 302
                assert await login(operator, TOKEN, guesser) == 302, "checked before the penalty"
            assert not all(task.done() for task in storm), "the guesser's tries still wait"
            statuses = await asyncio.gather(*storm)
        assert set(statuses) == {401, 429}, "never a 500"
        assert statuses.count(401) == FREE_TRIES + 4, "after 0,0,0,1,2,4,8 s the next waits >30 s"
        assert descendants(server.pid) == []
    finally:
        said = stop_serve(server)
    assert said.count("wrong token from 203.0.113.5") == STORM, "every refused try is logged"
    assert "6.6.6.6" not in said, "what the client wrote is not believed"


@pytest.mark.slow
async def test_max_consoles_holds_under_a_burst_of_tabs(tmp_path):
    """Six tabs at once against --max-consoles 2: two consoles start, the four others are told
    why in one line and closed; a tab closed frees its place."""
    port = free_port()
    server = start_serve(tmp_path / "a.db", port, "--no-warm", "--max-consoles", "2")
    url = f"http://127.0.0.1:{port}/ws?width=120&height=40"
    try:
        async with aiohttp.ClientSession() as http:
            sockets = await asyncio.gather(*(http.ws_connect(url) for _ in range(6)))
            first = [await socket.receive(timeout=60) for socket in sockets]
            refused = [
                (socket, message)
                for socket, message in zip(sockets, first)
                if b"the most this server allows" in (message.data or b"")
            ]
            assert len(refused) == 4, [m.data[:80] for m in first]
            line = refused[0][1].data.decode().strip()
            assert line == (
                "astiop serve: 2 consoles are open, the most this server allows "
                "(--max-consoles 2): close a tab, then reload this page."
            )
            for socket, _ in refused:
                closing = await socket.receive(timeout=10)
                assert closing.type == aiohttp.WSMsgType.CLOSE and closing.data == 1013
            kept = [socket for socket in sockets if socket not in [r[0] for r in refused]]
            terminal = Terminal()
            await read_until(kept[0], terminal, r"Dashboard")
            assert len(consoles_of(server.pid)) == 2
            await kept[0].close()
            wait_until(lambda: len(consoles_of(server.pid)) == 1, what="a console to end")
            wait_until(  # the server frees the place once it has seen the console end
                lambda: "ended (1 open)" in server.log_path.read_text(errors="replace"),
                what="the server to free its place",
            )
            again = await http.ws_connect(url)
            await read_until(again, Terminal(), r"Dashboard")  # its place was freed
            assert len(consoles_of(server.pid)) == 2
            await again.close()
            await kept[1].close()
            wait_until(lambda: descendants(server.pid) == [], what="every process to end")
    finally:
        log = stop_serve(server)
    assert log.count("console refused to 127.0.0.1: 2 open") == 4, log


@pytest.mark.slow
async def test_a_page_elsewhere_cannot_open_a_console_nor_stop_nor_read(tmp_path):
    port = free_port()
    server = start_serve(tmp_path / "a.db", port, "--no-warm")
    url = f"http://127.0.0.1:{port}"
    evil = {"Origin": "http://evil.example"}
    try:
        async with aiohttp.ClientSession() as http:
            async with http.get(url + "/ws", headers=evil) as r:
                assert r.status == 403
            async with http.post(url + "/estop", headers={**evil, "X-Astiop": "estop"}) as r:
                assert r.status == 403
            async with http.post(url + "/estop") as r:  # a plain form post (no custom header)
                assert r.status == 403
            rebound = {"Host": f"evil.example:{port}", "Origin": f"http://evil.example:{port}"}
            async with http.get(url + "/", headers=rebound) as r:  # DNS rebinding
                assert r.status == 403
            async with http.get(url + "/ws", headers=rebound) as r:
                assert r.status == 403
        assert descendants(server.pid) == []
    finally:
        stop_serve(server)
    store = Store(tmp_path / "a.db")
    assert store.estop_latch() is None, "nothing latched the E-STOP"
    store.close()


def opened(log: str) -> list[int]:
    return [int(pid) for pid in re.findall(r"console (\d+) opened", log)]


@pytest.mark.slow
async def test_a_warm_console_waits_for_the_next_tab_and_nothing_outlives_the_server(tmp_path):
    port = free_port()
    server = start_serve(tmp_path / "a.db", port)
    url = f"http://127.0.0.1:{port}"
    try:
        wait_until(lambda: len(descendants(server.pid)) == 1, what="the spare console")
        (spare,) = descendants(server.pid)

        def resting() -> bool:  # its imports done, it waits on stdin
            before = cpu_s(spare)
            time.sleep(1.0)
            return cpu_s(spare) - before < 0.03

        wait_until(resting, timeout=30, what="the spare to wait without using the CPU")
        async with aiohttp.ClientSession() as http:
            ws = await http.ws_connect(url + "/ws?width=120&height=40")
            terminal = Terminal()
            await read_until(ws, terminal, r"battery\s+\S+\s+\d+\.\d %")
            assert terminal.screen.columns == 120 and "Dashboard" in terminal.text()
            assert opened(server.log_path.read_text()) == [spare], "the tab took the spare"
            wait_until(lambda: len(descendants(server.pid)) == 2, what="the next spare")
            await ws.close()
            wait_until(lambda: spare not in descendants(server.pid), what="the tab's console")
        left = descendants(server.pid)
        assert len(left) == 1 and left != [spare]
    finally:
        stop_serve(server)
    assert not any(Path(f"/proc/{pid}").exists() for pid in [spare, *left])


def cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.slow
async def test_the_estop_button_latches_for_every_console(tmp_path):
    port = free_port()
    server = start_serve(tmp_path / "a.db", port)
    url = f"http://127.0.0.1:{port}"
    try:
        async with aiohttp.ClientSession() as http:
            ws = await http.ws_connect(url + "/ws?width=120&height=40")
            terminal = Terminal()
            await read_until(ws, terminal, r"robot\s+CHARGING")
            same_page = {"Origin": url, "X-Astiop": "estop"}
            async with http.post(url + "/estop", headers=same_page) as r:
                body = await r.json()
                assert r.status == 200, body
            assert body["engaged"] and body["ok"] and "E-STOP ENGAGED" in body["message"]
            store = Store(tmp_path / "a.db")
            latch = store.estop_latch()
            store.close()
            assert latch and latch["by"] == "serve: browser at 127.0.0.1"
            await read_until(ws, terminal, r"E.STOPPED")  # the open console follows the latch
            async with http.get(url + "/estop") as r:
                assert (await r.json())["engaged"]
            await ws.close()
    finally:
        stop_serve(server)


def test_serve_refuses_in_one_line(tmp_path):
    db = str(tmp_path / "a.db")
    off = run_cli("--db", db, "serve", "--host", "0.0.0.0")
    assert off.returncode == 2 and "needs a token" in off.stderr and off.stderr.count("\n") == 1
    given = run_cli("--db", db, "serve", "--token", TOKEN)
    assert given.returncode == 2 and "`ps`" in given.stderr
    loose = tmp_path / "token"
    loose.write_text(TOKEN)
    loose.chmod(0o644)
    bad = run_cli("--db", db, "serve", "--token-file", str(loose))
    assert bad.returncode == 2 and "chmod 600" in bad.stderr


@pytest.mark.slow
def test_a_port_in_use_is_said(tmp_path):
    port = free_port()
    server = start_serve(tmp_path / "a.db", port)
    try:
        second = run_cli("--db", str(tmp_path / "a.db"), "serve", "--port", str(port))
        assert second.returncode == 2 and f"cannot listen on 127.0.0.1:{port}" in second.stderr
    finally:
        stop_serve(server)


async def send_keys(ws, text: str) -> None:
    await ws.send_str(json.dumps(["stdin", text]))


def pose_x(terminal: Terminal) -> float | None:
    found = re.search(r"pose\s+x\s+(-?\d+\.\d+) m", terminal.text())
    return float(found.group(1)) if found else None


@pytest.mark.slow
@pytest.mark.ros
async def test_every_tab_sees_one_shared_simulated_robot_and_its_estop(tmp_path):
    """...and its watches are evaluated with no tab open (the server's `astiop watch run`)."""
    require_ros()
    port = free_port()
    store = Store(tmp_path / "a.db")
    try:  # the simulated battery is at 85 %
        store.add_watch(**Watch("battery", "<", 90.0).row())
    finally:
        store.close()
    server = start_serve(tmp_path / "a.db", port, "--no-warm", sim="shared")
    url = f"http://127.0.0.1:{port}"
    try:
        store = Store(tmp_path / "a.db")
        try:
            deadline = time.monotonic() + 60
            while not store.list_alerts() and time.monotonic() < deadline:
                time.sleep(0.2)
            (alert,) = store.list_alerts()
        finally:
            store.close()
        assert alert["watch_id"] == 1 and alert["reading"].startswith("85."), alert
        async with aiohttp.ClientSession() as http:
            async with http.get(url + "/") as page:
                text = await page.text()
            assert "shared by every tab" in text
            # never on this machine's graph, where a real base may listen: a domain of its own
            domain = re.search(r"ROS_DOMAIN_ID=(\d+)", text)
            assert domain and domain[1] != os.environ["ROS_DOMAIN_ID"], text
            with ros_client("graph_watch") as client:
                time.sleep(1.5)
                assert not client.node.get_subscriptions_info_by_topic("/cmd_vel")
            one, two = Terminal(), Terminal()
            first = await http.ws_connect(url + "/ws?width=120&height=40")
            second = await http.ws_connect(url + "/ws?width=120&height=40")
            pumps = [
                asyncio.create_task(_pump(first, one)),
                asyncio.create_task(_pump(second, two)),
            ]
            await _shown(one, r"pose\s+x\s+1\.15 m", timeout=60)
            await _shown(two, r"pose\s+x\s+1\.15 m", timeout=60)
            await send_keys(first, "\x1bOQ")  # F2: Chat
            await _shown(one, r"Ask the robot")
            # both tabs are consoles of one robot: the one that took control first drives it;
            # the other takes it over (ctrl+t, asked), as an operator would
            await _shown(one, r"in control|WATCHING", timeout=30)
            if one.has("WATCHING"):
                await send_keys(first, "\x14")
                await _shown(one, r"Take control of the robot from console")
                await send_keys(first, "y")
                await _shown(one, r"in control", timeout=30)
                await _shown(two, r"WATCHING", timeout=30)  # and that one is told
            await send_keys(first, "go to shipping\r")
            await _shown(one, r"you: go to shipping")
            await _shown(one, r"Run this command\? It moves the robot", timeout=60)
            await send_keys(first, "y")
            # the robot the first tab sent away is the one the second tab shows
            await _shown(two, r"pose\s+x\s+(?!1\.15)\d+\.\d+ m", timeout=60)
            async with http.post(url + "/estop", headers={"Origin": url, "X-Astiop": "estop"}) as r:
                body = await r.json()
                assert r.status == 200 and body["ok"], body
            # stopped from the server's own process (no `astiop estop` started), then recorded
            assert body["robot"] == "the robot was told to stop" and body["recorded"], body
            await _shown(two, r"E.STOPPED", timeout=30)
            await asyncio.sleep(1.5)  # the base brakes to a stop (the screen follows it live)
            settled = pose_x(two)
            await asyncio.sleep(2)
            await _shown(two, r"pose")
            assert abs(pose_x(two) - settled) < 0.05, "the shared robot stays stopped"
            processes = descendants(server.pid)
            names = []
            for pid in processes:
                with contextlib.suppress(OSError):  # a process may end meanwhile
                    names.append(Path(f"/proc/{pid}/cmdline").read_bytes())
            assert any(b"sim\0node" in n for n in names), "the simulator runs under the server"
            assert any(b"watch\0run" in n for n in names), "and its watches' runner"
            for pump in pumps:
                pump.cancel()
            await first.close()
            await second.close()
    finally:
        stop_serve(server)
    assert not any(Path(f"/proc/{pid}").exists() for pid in processes), "nothing outlives it"
