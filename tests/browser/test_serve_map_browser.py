"""The Dashboard's map in `astiop serve`'s browser tab (headless Chromium, Playwright): a mouse
drag gives the point the heading dragged; a click on the floor opens the point's menu, and
sending from it asks the same confirmation as a typed goal, after which the robot drives there. Screenshots kept in test-artifacts/browser/."""

from __future__ import annotations

import asyncio
import re

import pytest

from tests.browser import CHROMIUM, FLAGS, Tab, browser_or_skip
from tests.web_console import ENV, free_port, start_serve, stop_serve

pytestmark = pytest.mark.slow


def _cell_of(tab: Tab, text: str) -> tuple[int, int]:
    """(column, row) of the first character of `text` on the console's screen."""
    for row, line in enumerate(tab.terminal.screen.display):
        col = line.find(text)
        if col >= 0:
            return col, row
    raise AssertionError(f"{text!r} not on the screen:\n{tab.terminal.text()}")


async def test_a_click_on_the_map_in_the_browser_sends_the_robot_after_the_question(tmp_path):
    async_playwright = browser_or_skip()
    db, port = tmp_path / "m.db", free_port()
    server = start_serve(db, port, "--no-warm", env=ENV)  # loopback: no token
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            context = await browser.new_context(viewport={"width": 1400, "height": 900})
            tab = Tab(await context.new_page())
            page = tab.page
            await page.goto(f"http://127.0.0.1:{port}/")
            await tab.shows(r"battery\s+\S+\s+\d+\.\d %")
            await tab.shows(r"inspection_zone_a")  # a zone's name is written inside it
            screen = await page.locator(".xterm-screen").bounding_box()
            cols, rows = tab.terminal.screen.columns, tab.terminal.screen.lines
            cw, ch = screen["width"] / cols, screen["height"] / rows
            col, row = _cell_of(tab, "inspection_zone_a")
            col += len("inspection_zone_a") // 2  # the middle of the zone: open floor
            at_x, at_y = screen["x"] + (col + 0.5) * cw, screen["y"] + (row + 0.5) * ch
            # pressed there and let go three rows up: the point, facing the way dragged (+y)
            await page.mouse.move(at_x, at_y)
            await page.mouse.down()
            await page.mouse.move(at_x, at_y - 3 * ch, steps=4)
            await page.mouse.up()
            await tab.shows(r"Send this robot here \(\d+\.\d\d, \d+\.\d\d\), facing 90°")
            await tab.shot("map-0-dragged-heading")
            await page.keyboard.press("Escape")  # closed: nothing sent
            for _ in range(100):
                if not tab.terminal.has("Send this robot here"):
                    break
                await asyncio.sleep(0.1)
            assert not tab.terminal.has("Send this robot here"), tab.terminal.text()
            await page.mouse.click(at_x, at_y)
            await tab.shows(r"Send this robot here \(\d+\.\d\d, \d+\.\d\d\)")
            point = re.search(r"The point \((\d+\.\d\d), (\d+\.\d\d)\) m", tab.terminal.text())
            assert point is not None, tab.terminal.text()
            x, y = point.groups()
            await tab.shot("map-1-point-menu")
            await page.keyboard.press("Enter")
            await tab.shows(r"Run this command\? It moves the robot")
            await tab.shows(rf"x: {x}, y: {y}")
            await tab.shot("map-2-confirm")
            await page.keyboard.press("y")
            await tab.shows(rf"goal\s+\({float(x):g}, {float(y):g}\)")
            await tab.shot("map-3-driving")
            await browser.close()
    finally:
        stop_serve(server)
