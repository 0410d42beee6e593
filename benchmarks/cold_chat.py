"""`astiop chat` in a new process with the embedded model, timed end to end, and the warm turn.

    python benchmarks/cold_chat.py [--runs N] [--request TEXT] [--other TEXT] [--checkout DIR]

Each cold figure is the wall time of `astiop chat REQUEST --json` from process start to exit
(the model not yet started): with an empty prompt cache ("no cache"), with the cache the
previous run left ("restored"), and with the cache left by another request ("restored, other
request": only the fixed prompts are reused). The warm figure is one agent turn in a process
whose model already answered both requests (as in the console), the two taking turns. Everything runs on the simulator with a
throw-away database, settings file and cache folder; `--checkout` times another checkout of
astiop (e.g. a `git worktree` of an older commit) with this venv.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WARM = """
import asyncio, json, sys, time
from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.config import load_settings
from astiop.robot.factory import make_robot_gateway
from astiop.store import Store

requests, runs = sys.argv[1:3], int(sys.argv[3])
settings = load_settings()
store = Store(settings.db)
gateway = make_robot_gateway(settings, store)
endpoint = open_endpoint(
    settings.llm.model, threads=settings.llm.threads, n_ctx=settings.llm.context
)
agent = Agent(gateway, endpoint, store, confirm=lambda c: True, session="bench")

async def turns():
    out = []
    for i in range(runs + 2):
        t0 = time.perf_counter()
        result = await agent.turn(requests[i % 2])
        out.append({"s": time.perf_counter() - t0, "ttft_s": result.ttft_s,
                    "answer": result.answer})
        agent.history.clear()  # each turn the first of a conversation, as `astiop chat`
    return out

rows = asyncio.run(turns())
endpoint.close()
gateway.close()
print(json.dumps({"turns": rows[2:]}))
"""


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def cold_run(env: dict[str, str], request: str, cwd: str) -> dict:
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "astiop", "chat", request, "--json"],
        env=env,
        cwd=cwd,  # not a checkout: PYTHONPATH picks the one timed
        capture_output=True,
        text=True,
        timeout=600,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"astiop chat failed ({proc.returncode}): {proc.stderr.strip()[-300:]}")
    data = json.loads(proc.stdout)
    timings = data.get("timings") or {}
    return {
        "wall_s": wall,
        "turn_s": timings.get("total_s"),
        "ttft_s": timings.get("ttft_s"),
        "answer": data.get("answer"),
    }


def summary(name: str, rows: list[dict]) -> dict:
    walls = [r["wall_s"] for r in rows]
    out = {
        "case": name,
        "runs": len(rows),
        "median_wall_s": round(statistics.median(walls), 2),
        "min_wall_s": round(min(walls), 2),
        "max_wall_s": round(max(walls), 2),
    }
    turns = [r["turn_s"] for r in rows if r.get("turn_s") is not None]
    ttfts = [r["ttft_s"] for r in rows if r.get("ttft_s") is not None]
    if turns:
        out["median_turn_s"] = round(statistics.median(turns), 2)
    if ttfts:
        out["median_ttft_s"] = round(statistics.median(ttfts), 2)
    out["answers"] = sorted({r["answer"] for r in rows})
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--request", default="what is the battery level?")
    parser.add_argument("--other", default="where is the robot?")
    parser.add_argument("--checkout", type=Path, default=Path(__file__).resolve().parents[1])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    results, loads = [], [load()]
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp) / "cache"
        env = {
            **os.environ,
            "PYTHONPATH": str(args.checkout.resolve()),
            "ASTIOP_CONFIG": str(Path(tmp) / "config.toml"),
            "ASTIOP_DB": str(Path(tmp) / "astiop.db"),
            "ASTIOP_MODEL": "embedded",
            "XDG_CACHE_HOME": str(cache),
        }
        env.pop("ASTIOP_ROBOT", None)
        t0 = time.perf_counter()
        # the typer app and its commands (in astiop.cli itself before it was split)
        app = "try:\n import astiop.cli.commands\nexcept ImportError:\n import astiop.cli"
        subprocess.run([sys.executable, "-c", app], env=env, cwd=tmp, check=True)
        imports = time.perf_counter() - t0

        rows = []
        for _ in range(args.runs):
            shutil.rmtree(cache, ignore_errors=True)
            rows.append(cold_run(env, args.request, tmp))
        results.append(summary("cold, no cache", rows))
        loads.append(load())

        cold_run(env, args.request, tmp)  # leaves the cache of this request
        rows = [cold_run(env, args.request, tmp) for _ in range(args.runs)]
        results.append(summary("cold, restored", rows))
        loads.append(load())

        rows = [cold_run(env, args.other, tmp) for _ in range(args.runs)]
        results.append(summary("cold, restored, other request", rows))
        loads.append(load())

        proc = subprocess.run(
            [sys.executable, "-c", WARM, args.request, args.other, str(args.runs)],
            env=env,
            cwd=tmp,
            capture_output=True,
            text=True,
            timeout=600,
            check=True,
        )
        turns = json.loads(proc.stdout.strip().splitlines()[-1])["turns"]
        warm = [{"wall_s": t["s"], "ttft_s": t["ttft_s"], "answer": t["answer"]} for t in turns]
        results.append(summary("warm turn (in process)", warm))
        loads.append(load())

    report = {
        "checkout": str(args.checkout),
        "python_start_and_import_the_cli_s": round(imports, 2),
        "load_average_1_5_15": loads,
        "results": results,
    }
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        print(f"checkout {args.checkout}; python start and the CLI's imports {imports:.2f} s")
        for r in results:
            extra = "".join(
                f"  {k.removeprefix('median_')} {r[k]:.2f}"
                for k in ("median_turn_s", "median_ttft_s")
                if k in r
            )
            print(
                f"{r['case']:<32} median {r['median_wall_s']:.2f} s "
                f"(min {r['min_wall_s']:.2f}, max {r['max_wall_s']:.2f}, n={r['runs']}){extra}"
            )
        print("load average (1, 5, 15 min) at each step:", " | ".join(loads))
    return 0


if __name__ == "__main__":
    sys.exit(main())
