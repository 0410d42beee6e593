"""The first answer on a fresh install, asked in the console one second after it opens.

    python benchmarks/first_answer_console.py [--runs N] [--request TEXT] [--at S]

Each run is a new process with a new config, store and an empty cache (nothing of the embedded
model's prompts kept): the console built as `astiop` builds it (`make_app`, the simulator, the
embedded model), driven headless with Textual's Pilot. When the Dashboard shows, it waits
`--at` seconds, goes to the Chat screen, types the request and sends it; once the model's
warm-up is over, it asks the same again (the model's own first answer). Figures: the seconds
from each request sent to its answer shown, and the answers.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

RUN = """
import asyncio, json, sys, time
from textual.widgets import Input
from astiop.app import make_app
from astiop.config import load_settings
from astiop.store import Store

request, at = sys.argv[1], float(sys.argv[2])
settings = load_settings()
store = Store(settings.db)

async def ask(app, pilot):
    before = len(app.screen.query(".answer"))
    app.screen.query_one(Input).value = request
    t0 = time.perf_counter()
    await pilot.press("enter")
    while True:
        shown = [str(w.render()) for w in list(app.screen.query(".answer"))[before:]]
        if any(" · " in s for s in shown):  # the turn's status line: the answer is in
            break
        if time.perf_counter() - t0 > 600:
            raise SystemExit("no answer in 600 s")
        await asyncio.sleep(0.02)
    answer = " | ".join(s for s in shown if s.strip() and "thinking" not in s)
    return time.perf_counter() - t0, answer


async def main():
    t_start = time.perf_counter()
    app = make_app(settings, store)
    async with app.run_test(size=(120, 40)) as pilot:
        t_open = time.perf_counter()  # the Dashboard shows
        await asyncio.sleep(at)
        await pilot.press("f2")
        await pilot.pause()
        first_s, first = await ask(app, pilot)
        while app.services.endpoint.warming:
            await asyncio.sleep(0.1)
        await app.workers.wait_for_complete()
        warmed_s = time.perf_counter() - t_open
        then_s, then = await ask(app, pilot)
    return {"open_s": t_open - t_start, "answer_s": first_s, "answer": first,
            "warmed_s": warmed_s, "then_s": then_s, "then": then}

print(json.dumps(asyncio.run(main())))
"""


def run(request: str, at: float, checkout: Path) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = {
            **os.environ,
            "PYTHONPATH": str(checkout),
            "ASTIOP_CONFIG": str(Path(tmp) / "config.toml"),
            "ASTIOP_DB": str(Path(tmp) / "astiop.db"),
            "ASTIOP_MODEL": "embedded",
            "XDG_CACHE_HOME": str(Path(tmp) / "cache"),  # empty: a fresh install
        }
        env.pop("ASTIOP_ROBOT", None)
        proc = subprocess.run(
            [sys.executable, "-c", RUN, request, str(at)],
            env=env,
            cwd=tmp,
            capture_output=True,
            text=True,
            timeout=900,
        )
    if proc.returncode != 0:
        raise SystemExit(f"failed ({proc.returncode}): {proc.stderr.strip()[-600:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--request", default="what is the battery level?")
    parser.add_argument("--at", type=float, default=1.0, help="seconds after the console opens")
    parser.add_argument("--checkout", type=Path, default=Path(__file__).resolve().parents[1])
    args = parser.parse_args()
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    rows = [run(args.request, args.at, args.checkout.resolve()) for _ in range(args.runs)]
    turns = [r["answer_s"] for r in rows]
    print(
        f"asked at +{args.at:g} s: first answer median {statistics.median(turns):5.2f} s "
        f"(min {min(turns):.2f}, max {max(turns):.2f}, n={len(rows)}); console opened in "
        f"{statistics.median(r['open_s'] for r in rows):.2f} s"
    )
    print("  answers:", sorted({r["answer"][:160] for r in rows}))
    then = [r["then_s"] for r in rows]
    print(
        f"warm-up over at +{statistics.median(r['warmed_s'] for r in rows):.1f} s; the same asked "
        f"then: median {statistics.median(then):5.2f} s (min {min(then):.2f}, max {max(then):.2f})"
    )
    print("  answers:", sorted({r["then"][:160] for r in rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
