"""Headless Chromium from the system's packages, driven by Playwright (its own browser download
does not reach this network), and what a page's console shows (its websocket through pyte)."""

from __future__ import annotations

import asyncio
import os
import shutil
import time
from pathlib import Path

import pytest

from tests.web_console import Terminal

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "browser"
# as root, with no network but the loopback: no sandbox, nothing fetched in the background
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def browser_or_skip():
    """Playwright's async API, or a skip that says what is missing (a failure where CI requires
    the browser tests: REQUIRE_BROWSER_TESTS=1)."""
    missing = None
    try:
        from playwright.async_api import async_playwright
    except ImportError:
        missing = "playwright is not installed (pip install -e '.[test]')"
    if missing is None and CHROMIUM is None:
        missing = "no chromium on PATH (apt-get install chromium)"
    if missing:
        if os.environ.get("REQUIRE_BROWSER_TESTS") == "1":
            pytest.fail(f"browser tests are required here: {missing}")
        pytest.skip(missing)
    return async_playwright


class Tab:
    """A page with its console's screen read from the websocket's frames."""

    def __init__(self, page):
        self.page = page
        self.terminal = Terminal()
        page.on("websocket", self._socket)

    def _socket(self, ws) -> None:
        ws.on("framereceived", self._received)
        ws.on("framesent", self._sent)

    def _received(self, payload) -> None:
        if isinstance(payload, bytes):
            self.terminal.feed(payload)

    def _sent(self, payload) -> None:
        if isinstance(payload, str) and payload.startswith('["resize"'):
            import json

            size = json.loads(payload)[1]
            self.terminal.resize(size["width"], size["height"])

    async def shows(self, pattern: str, timeout: float = 60.0) -> None:
        """Until the screen shows `pattern`: on a CI machine running four workers on two cores
        (a tab's console and Chromium each), a step has been seen to take over 30 s."""
        deadline = time.monotonic() + timeout
        while not self.terminal.has(pattern):
            if time.monotonic() > deadline:
                raise AssertionError(f"{pattern!r} never shown:\n{self.terminal.text()}")
            await asyncio.sleep(0.1)

    async def shot(self, name: str) -> None:
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        await self.page.screenshot(path=str(ARTIFACTS / f"{name}.png"))
