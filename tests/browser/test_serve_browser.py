"""`astiop serve` in a real browser: headless Chromium (the system's) driven by Playwright. The
token asked first; every screen reached by its key; a Chat answer; the page's E-STOP button
stopping the robot for every tab and the database; keys a browser would take (ctrl+r reloads a
page, F5 too) reaching the console; closing the tabs leaving no process. Screenshots of each
screen are kept in test-artifacts/browser/."""

from __future__ import annotations

import asyncio
import re
import time
from pathlib import Path

import pytest

from astiop.store import Store
from tests.browser import CHROMIUM, FLAGS, Tab, browser_or_skip
from tests.web_console import ENV, descendants, free_port, start_serve, stop_serve

TOKEN = "browser-token-0123456789abcdef"
SCREENS = {  # key -> what only that screen shows
    "F2": r"Ask the robot",
    "F3": r"search prompt, answer, command",
    "F4": r"name\s+x \(m\)\s+y \(m\)",
    "F5": r"w fwd\s+s back",
    "F6": r"\^b Run",
    "F1": r"battery\s+\S+\s+\d+\.\d %",
}

pytestmark = pytest.mark.slow
# where a click only gives the page's terminal the keys: the Dashboard's robot panel (a click on
# its map opens the point's menu)
BESIDE_THE_MAP = {"x": 1100, "y": 120}


def opened(log: str) -> list[int]:
    return [int(pid) for pid in re.findall(r"console (\d+) opened", log)]


def latch(db):
    store = Store(db)
    try:
        return store.estop_latch()
    finally:
        store.close()


async def until(check, timeout: float = 20.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        await asyncio.sleep(0.1)


async def test_the_console_in_a_browser_behind_its_token(tmp_path):
    async_playwright = browser_or_skip()
    db, port = tmp_path / "a.db", free_port()
    server = start_serve(db, port, env={**ENV, "ASTIOP_SERVE_TOKEN": TOKEN})
    url = f"http://127.0.0.1:{port}/"
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            context = await browser.new_context(viewport={"width": 1400, "height": 900})
            tab = Tab(await context.new_page())
            page = tab.page
            await page.goto(url)
            assert page.url.endswith("/login")
            await tab.shot("0-login")
            await page.fill("#token", TOKEN)
            t_login = time.monotonic()
            await page.click("button[type=submit]")
            await tab.shows(SCREENS["F1"])  # a live battery on the Dashboard
            print(f"log-in to a live dashboard: {time.monotonic() - t_login:.2f} s")
            assert await page.title() == "astiop: simulator (one per tab)"
            await tab.shot("1-dashboard")
            await page.click("#terminal", position=BESIDE_THE_MAP)
            for n, (key, shown) in enumerate(SCREENS.items(), start=2):
                await page.keyboard.press(key)  # F5 reloads a page, F3 finds: not here
                await tab.shows(shown)
                await tab.shot(f"{n}-{key}")
            assert page.url.endswith(f":{port}/"), "no key left the page"

            await page.keyboard.press("F2")
            await tab.shows(SCREENS["F2"])
            await page.keyboard.type("what is the battery level?")
            await page.keyboard.press("Enter")
            await tab.shows(r"ros2 topic echo /battery_status")  # what ran, then the answer
            await tab.shows(r"battery \d+\.\d %, \d+\.\d+ V")
            await tab.shot("8-chat-answer")

            await page.keyboard.press("F1")
            await page.keyboard.press("Control+r")  # a browser's reload; here the console's key
            await tab.shows(r"not engaged")
            await page.click("#estop")  # the page's button: one click, on every screen
            await page.wait_for_selector("#latch.engaged")
            assert latch(db)["by"] == "serve: browser at 127.0.0.1"
            await tab.shows(r"E.STOPPED")
            await tab.shot("9-estop")

            second = Tab(await context.new_page())  # the same browser's cookie: no log-in
            await second.page.goto(url)
            await second.page.wait_for_selector("#latch.engaged")
            await second.shows(r"E.STOPPED")
            await second.shot("10-second-tab")

            # the E-STOP's own process latches again as it ends: released before that, the
            # E-STOP wins (a loaded machine: seconds)
            await until(lambda: "E-STOP engaged and latched" in server.log_path.read_text(),
                        what="the E-STOP's process to end")  # fmt: skip
            await page.click("#terminal", position=BESIDE_THE_MAP)
            await page.keyboard.press("Control+r")
            await tab.shows(r"Release the e-stop\?")
            await page.keyboard.press("y")
            await until(lambda: latch(db) is None, what="the release")
            await page.keyboard.press("Control+e")  # the console's own key, in the terminal
            await until(lambda: latch(db) is not None, what="ctrl+e")
            assert latch(db)["by"] != "serve: browser at 127.0.0.1"

            await page.keyboard.press("Control+p")  # the palette: every global key's second way
            await tab.shows(r"Search for commands")
            await page.keyboard.type("Screen: Logs")
            await tab.shows(r"Show the logs screen")
            await page.keyboard.press("Enter")
            await tab.shows(SCREENS["F3"])

            tabs = opened(server.log_path.read_text())
            assert len(tabs) == 2 and set(tabs) <= set(descendants(server.pid))
            await page.keyboard.press("Control+q")  # the console quits; the page says so
            await page.wait_for_selector("#ended", state="visible")
            await tab.shot("11-ended")
            await second.page.close(run_before_unload=False)
            await until(
                lambda: not set(tabs) & set(descendants(server.pid)), what="the tabs' consoles"
            )
            await browser.close()
        assert len(descendants(server.pid)) == 1, "only the spare waits for the next tab"
        kept = descendants(server.pid)
    finally:
        stop_serve(server)
    assert not any(Path(f"/proc/{pid}").exists() for pid in kept), "nothing outlives the server"


async def test_a_wrong_token_in_the_page_starts_nothing(tmp_path):
    async_playwright = browser_or_skip()
    db, port = tmp_path / "a.db", free_port()
    server = start_serve(db, port, "--no-warm", env={**ENV, "ASTIOP_SERVE_TOKEN": TOKEN})
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            page = await browser.new_page()
            await page.goto(f"http://127.0.0.1:{port}/")
            await page.fill("#token", "not-the-token-000000")
            await page.click("button[type=submit]")
            await page.wait_for_selector("text=Wrong token")
            await page.goto(f"http://127.0.0.1:{port}/ws")  # straight at the console: refused
            assert "log in first" in await page.content()
            await browser.close()
        assert descendants(server.pid) == []
    finally:
        stop_serve(server)


async def test_the_bell_shows_each_open_alert_within_a_second(tmp_path):
    """The page's E-STOP button raises the console's built-in alert, shown on the tab's bell; an
    alert written by another process (as `astiop watch run` writes one) is shown within 1 s;
    acknowledged, the bell is empty again. No sound: a count, a list, the tab's title."""
    async_playwright = browser_or_skip()
    db, port = tmp_path / "a.db", free_port()
    server = start_serve(db, port, "--no-warm")
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            tab = Tab(await (await browser.new_context()).new_page())
            page = tab.page
            await page.goto(f"http://127.0.0.1:{port}/")
            await tab.shows(SCREENS["F1"])
            await page.wait_for_function(
                "document.querySelector('#bell summary').textContent.includes('0 open')"
            )
            await page.click("#estop")
            await page.wait_for_selector("#bell.open.new", timeout=20_000)
            assert "E-STOP engaged by serve: browser at 127.0.0.1" in await page.text_content(
                "#bell ul"
            )
            assert (await page.title()).startswith("(1) astiop")

            store = Store(db)
            try:
                fired = store.fire_alert(
                    "bell-test", robot="astibot", kind="watch", message="battery below 20 %"
                )
                assert fired is not None
                written = time.monotonic()
                await page.wait_for_function(
                    "document.querySelector('#bell summary').textContent.includes('2 open')"
                )
                shown_s = time.monotonic() - written
                print(f"an alert on the tab's bell {shown_s:.2f} s after it was written")
                assert shown_s < 5, shown_s  # 0.5 s polls: well under 1 s on an idle machine
                assert "astibot: battery below 20 %" in await page.text_content("#bell ul")
                await page.click("#bell summary")  # opened: the list, the outline gone
                await page.wait_for_selector("#bell[open]:not(.new)", timeout=5_000)
                await tab.shot("bell")
                for alert in store.alerts_where(open_only=True):
                    store.acknowledge_alert(alert["id"], "test")
            finally:
                store.close()
            await page.wait_for_function(
                "document.querySelector('#bell summary').textContent.includes('0 open')"
            )
            assert not await page.query_selector("#bell.open")
            assert not (await page.title()).startswith("(")
            await page.close(run_before_unload=False)
            await browser.close()
    finally:
        stop_serve(server)
