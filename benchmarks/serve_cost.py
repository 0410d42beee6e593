"""What a browser tab's console costs against a terminal's, and how soon a page is live.

    python benchmarks/serve_cost.py [--seconds 20] [--opens 5] [--sim per-tab|shared]

The terminal console runs under tmux (a real terminal); the tab's console under `astiop serve`,
opened by headless Chromium (the system's, driven by Playwright). Both idle on the Dashboard on
the simulator with the rules model; CPU is the console process's own (user + system) over the
window, as a % of one core. The server keeps a spare console started ahead (its default);
"page → live dashboard" is from `page.goto` to the Dashboard's
battery line on the tab's screen (its websocket's bytes read by pyte). `--sim shared` serves one
simulated robot (`astiop sim node`, rclpy) to every tab; run it with the DDS variables on the
loopback (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, a ROS_DOMAIN_ID of its own). Opens are
8 s apart: a tab opened within ~5 s of the one before finds no spare ready and starts its own.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.browser import CHROMIUM, FLAGS, Tab  # noqa: E402
from tests.web_console import free_port, start_serve, stop_serve  # noqa: E402

SPARE_S = 8.0  # between opens: the next spare console is built (a ROS 2 robot's takes ~5 s)
LIVE = r"battery\s+\S+\s+\d+\.\d %"
TICK = os.sysconf("SC_CLK_TCK")


def cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def cpu_percent(pid: int, seconds: float) -> float:
    start, t0 = cpu_s(pid), time.monotonic()
    time.sleep(seconds)
    return 100 * (cpu_s(pid) - start) / (time.monotonic() - t0)


def terminal_console(folder: Path, seconds: float) -> float:
    session = f"astiop-bench-{os.getpid()}"
    exe = str(Path(sys.executable).with_name("astiop"))
    command = f"{exe} --db {folder / 'tty.db'} --model rules"
    subprocess.run(["tmux", "new-session", "-d", "-s", session, "-x", "155", "-y", "47", command])
    try:
        time.sleep(8)  # started and settled on the Dashboard
        pane = subprocess.run(
            ["tmux", "list-panes", "-t", session, "-F", "#{pane_pid}"],
            capture_output=True,
            text=True,
        ).stdout.split()[0]
        return cpu_percent(int(pane), seconds)
    finally:
        subprocess.run(["tmux", "kill-session", "-t", session])


async def browser_console(
    folder: Path, seconds: float, opens: int, sim: str
) -> tuple[float, list[float]]:
    from playwright.async_api import async_playwright

    port = free_port()
    server = start_serve(folder / "web.db", port, sim=sim)
    url = f"http://127.0.0.1:{port}/"
    live: list[float] = []
    try:
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            page = await browser.new_page(viewport={"width": 1400, "height": 900})
            tab = Tab(page)
            await page.goto(url)
            await tab.shows(LIVE)
            await asyncio.sleep(5)
            log = server.log_path.read_text()
            console = int(re.findall(r"console (\d+) opened", log)[-1])
            cpu = await asyncio.to_thread(cpu_percent, console, seconds)
            await page.close(run_before_unload=False)
            for _ in range(opens):
                tab = Tab(await browser.new_page(viewport={"width": 1400, "height": 900}))
                t0 = time.monotonic()
                await tab.page.goto(url)
                await tab.shows(LIVE)
                live.append(time.monotonic() - t0)
                await tab.page.close(run_before_unload=False)
                await asyncio.sleep(SPARE_S)
            await browser.close()
    finally:
        stop_serve(server)
    return cpu, live


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="CPU window per console")
    parser.add_argument("--opens", type=int, default=5, help="page opens timed")
    parser.add_argument(
        "--sim", default="per-tab", choices=["per-tab", "shared"], help="astiop serve --sim"
    )
    args = parser.parse_args()
    if CHROMIUM is None:
        sys.exit("serve_cost: no chromium on PATH (apt-get install chromium)")
    with tempfile.TemporaryDirectory(prefix="astiop-serve-cost-") as tmp:
        folder = Path(tmp)
        tty = terminal_console(folder, args.seconds)
        web, live = asyncio.run(browser_console(folder, args.seconds, args.opens, args.sim))
    print(f"load average at the end: {os.getloadavg()[0]:.2f} (2 cores)")
    print("| console idle on the Dashboard | CPU, % of a core |")
    print("| --- | --- |")
    print(f"| terminal (tmux) | {tty:.1f} |")
    print(f"| browser tab (serve --sim {args.sim}) | {web:.1f} ({web / tty:.2f}× the terminal's) |")
    print(
        f"page → live dashboard: median {statistics.median(live):.2f} s, "
        f"worst {max(live):.2f} s over {len(live)} opens"
    )


if __name__ == "__main__":
    main()
