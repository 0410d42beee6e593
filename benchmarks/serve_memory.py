"""The memory of N browser tabs' consoles under `astiop serve`, to size --max-consoles.

    python benchmarks/serve_memory.py [--tabs 3] [--model rules|embedded] [--sim per-tab|shared]

N websockets are opened as N tabs would be (no browser), each read until its Dashboard is live;
then the RSS and PSS (proportional: shared pages split between the processes sharing them) of
every process under the server (consoles and what they started: the embedded model's server)
are summed. The server itself is not counted.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import tempfile
import time
from pathlib import Path

import aiohttp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.web_console import ENV, Terminal, descendants, free_port, start_serve, stop_serve  # noqa: E402

LIVE = r"battery\s+\S+\s+\d+\.\d %"


def kib(pid: int, path: str, key: str) -> int:
    try:
        for line in Path(f"/proc/{pid}/{path}").read_text().splitlines():
            if line.startswith(key):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


async def open_tabs(url: str, tabs: int, server_pid: int) -> None:
    async with aiohttp.ClientSession() as http:
        sockets = [await http.ws_connect(url) for _ in range(tabs)]
        for socket in sockets:
            terminal, deadline = Terminal(), time.monotonic() + 180
            while not terminal.has(LIVE) and time.monotonic() < deadline:
                message = await socket.receive(timeout=180)
                if message.type == aiohttp.WSMsgType.BINARY:
                    terminal.feed(message.data)
        await asyncio.sleep(10)  # the model loaded, the first samples drawn
        pids = descendants(server_pid)
        rss = sum(kib(p, "status", "VmRSS:") for p in pids) / 1024
        pss = sum(kib(p, "smaps_rollup", "Pss:") for p in pids) / 1024
        print(
            f"{tabs} tabs: {len(pids)} processes, RSS {rss:.0f} MiB ({rss / tabs:.0f} a tab), "
            f"PSS {pss:.0f} MiB ({pss / tabs:.0f} a tab)"
        )
        for socket in sockets:
            await socket.close()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--tabs", type=int, default=3)
    parser.add_argument("--model", default="rules")
    parser.add_argument("--sim", default="per-tab")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        port = free_port()
        server = start_serve(
            Path(tmp) / "a.db", port, "--no-warm", "--max-consoles", str(args.tabs),
            env=ENV, model=args.model, sim=args.sim,
        )  # fmt: skip
        try:
            asyncio.run(
                open_tabs(f"http://127.0.0.1:{port}/ws?width=120&height=40", args.tabs, server.pid)
            )
        finally:
            stop_serve(server)


if __name__ == "__main__":
    main()
