"""The first answer in a new console on a robot whose prompts the embedded model never saw.

    python benchmarks/first_answer.py [--runs N] [--request TEXT]

Each run is a new process with an empty prompt cache (a fresh install, or a robot never seen:
its planning prompt is generated from its profile), on the simulator. Three cases:
"not warmed" (the question asked at once, as before the console warmed its model), "warmed"
(the console opened, its warm-up done — `astiop.agent.warm` — then the question), and "asked
during the warm-up" (the question sent as soon as the warm-up starts). Figures: the turn's
seconds from the question to its answer, and how long the warm-up took after the model loaded.
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
from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.agent.warm import warm
from astiop.config import load_settings
from astiop.robot.factory import make_robot_gateway
from astiop.store import Store

case, request = sys.argv[1], sys.argv[2]
settings = load_settings()
store = Store(settings.db)
gateway = make_robot_gateway(settings, store)
endpoint = open_endpoint(settings.llm.model, threads=settings.llm.threads, n_ctx=settings.llm.context)
agent = Agent(gateway, endpoint, store, confirm=lambda c: True, session="bench")

async def main():
    await asyncio.to_thread(endpoint.client)  # the model loaded, as the console's first second
    warm_s = None
    if case == "warmed":
        warm_s = await warm(endpoint, gateway, store, settings.llm.mode)
    elif case == "during":
        task = asyncio.ensure_future(warm(endpoint, gateway, store, settings.llm.mode))
        await asyncio.sleep(0.2)
    t0 = time.perf_counter()
    result = await agent.turn(request)
    turn_s = time.perf_counter() - t0
    if case == "during":
        warm_s = await task
    return {"turn_s": turn_s, "warm_s": warm_s, "answer": result.answer}

print(json.dumps(asyncio.run(main())))
endpoint.close()
gateway.close()
"""


def run(case: str, request: str, checkout: Path) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = {
            **os.environ,
            "PYTHONPATH": str(checkout),
            "ASTIOP_CONFIG": str(Path(tmp) / "config.toml"),
            "ASTIOP_DB": str(Path(tmp) / "astiop.db"),
            "ASTIOP_MODEL": "embedded",
            "XDG_CACHE_HOME": str(Path(tmp) / "cache"),  # empty: nothing of this robot kept
        }
        env.pop("ASTIOP_ROBOT", None)
        proc = subprocess.run(
            [sys.executable, "-c", RUN, case, request],
            env=env,
            cwd=tmp,
            capture_output=True,
            text=True,
            timeout=900,
        )
    if proc.returncode != 0:
        raise SystemExit(f"{case}: failed ({proc.returncode}): {proc.stderr.strip()[-400:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--request", default="what is the battery level?")
    parser.add_argument("--checkout", type=Path, default=Path(__file__).resolve().parents[1])
    args = parser.parse_args()
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for case, label in (
        ("cold", "not warmed"),
        ("warmed", "warmed"),
        ("during", "asked during the warm-up"),
    ):
        rows = [run(case, args.request, args.checkout.resolve()) for _ in range(args.runs)]
        turns = [r["turn_s"] for r in rows]
        warms = [r["warm_s"] for r in rows if r["warm_s"] is not None]
        line = (
            f"{label:<26} first answer median {statistics.median(turns):5.2f} s "
            f"(min {min(turns):.2f}, max {max(turns):.2f}, n={len(rows)})"
        )
        if warms:
            line += f"; warm-up median {statistics.median(warms):.2f} s"
        print(line)
        print("  answers:", sorted({r["answer"] for r in rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
