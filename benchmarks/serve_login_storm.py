"""A storm of wrong tokens against `astiop serve`'s log-in, and how soon the right token gets in.

    python benchmarks/serve_login_storm.py [--tries 10000] [--proxy]

N wrong tokens are posted at once from one client (`--proxy`: through a trusted proxy on the
loopback, the client named by X-Forwarded-For); while they are answered, the right token is
posted from another client and from the guesser's own address. Prints the answers' statuses,
the right token's time to its cookie, and the storm's duration.
"""

from __future__ import annotations

import argparse
import asyncio
import collections
import sys
import tempfile
import time
from pathlib import Path

import aiohttp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.web_console import ENV, free_port, start_serve, stop_serve  # noqa: E402

TOKEN = "benchmark-token-0123456789"


async def storm(url: str, tries: int, proxy: bool) -> None:
    guesser = {"X-Forwarded-For": "203.0.113.5"} if proxy else {}
    other = {"X-Forwarded-For": "203.0.113.9"} if proxy else {}

    async def login(http, token: str, headers: dict) -> int:
        try:
            async with http.post(
                url, data={"token": token}, headers=headers, allow_redirects=False
            ) as r:
                return r.status
        except aiohttp.ClientError as exc:
            return type(exc).__name__

    async def right_token(headers: dict) -> tuple[str, float]:
        # another process (curl), as an operator's browser is: not queued behind the storm's
        # own client
        said = [f"-H{k}: {v}" for k, v in headers.items()]
        curl = await asyncio.create_subprocess_exec(
            "curl", "-s", "-o", "/dev/null", "-w", "%{http_code} %{time_total}",
            "--data-urlencode", f"token={TOKEN}", *said, url,
            stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        status, seconds = (await curl.communicate())[0].decode().split()
        return status, float(seconds)

    started = time.monotonic()
    times: dict[str, list[float]] = {"another client": [], "the guesser's address": []}
    statuses_right: set[str] = set()
    async with aiohttp.ClientSession(connector=aiohttp.TCPConnector(limit=0)) as http:
        tasks = [asyncio.ensure_future(login(http, f"wrong-{i}", guesser)) for i in range(tries)]
        while not all(t.done() for t in tasks):  # the right token, every 0.5 s of the storm
            for who, headers in (("another client", other), ("the guesser's address", guesser)):
                status, seconds = await right_token(headers)
                statuses_right.add(status)
                times[who].append(seconds)
            await asyncio.sleep(0.5)
        statuses = await asyncio.gather(*tasks)
    took = time.monotonic() - started
    for who, seconds in times.items():
        seconds.sort()
        print(
            f"right token from {who}, {len(seconds)} tries during the storm: median "
            f"{seconds[len(seconds) // 2]:.3f} s, max {seconds[-1]:.3f} s"
        )
    print(f"right token answers: {sorted(statuses_right)}")
    print(f"{tries} wrong tokens: {dict(collections.Counter(statuses))} in {took:.1f} s")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--tries", type=int, default=10_000)
    parser.add_argument("--proxy", action="store_true")
    args = parser.parse_args()
    env = {**ENV, "ASTIOP_SERVE_TOKEN": TOKEN}
    if args.proxy:
        env["ASTIOP_SERVE__TRUSTED_PROXIES"] = "127.0.0.1"
    with tempfile.TemporaryDirectory() as tmp:
        port = free_port()
        server = start_serve(Path(tmp) / "a.db", port, "--no-warm", env=env)
        try:
            asyncio.run(storm(f"http://127.0.0.1:{port}/login", args.tries, args.proxy))
        finally:
            log = stop_serve(server)
        print(f"server log: {log.count('wrong token from')} wrong tries logged, "
              f"{log.count('Error')} errors")  # fmt: skip


if __name__ == "__main__":
    main()
