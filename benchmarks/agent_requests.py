"""Held-out operator requests through the agent, on seeded simulators: the right command, no
wrong actuation, and answers that agree with what the simulator reported.

    python benchmarks/agent_requests.py [--model rules|embedded|SPEC] [--mode tool|command]
                                        [--threads N] [--interpretation grounded|raw] [--json]

A request passes when every command it names ran and no other actuation did. The answer is
checked against the simulator's own state (battery, position, obstacle count, state word, load,
health) for the topics the request names, and for loops and unsupported claims.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import tempfile
import time
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from astiop.agent import grounding  # noqa: E402
from astiop.agent.facts import facts_of
from astiop.agent.models.reply_stream import repeating  # noqa: E402
from astiop.agent.models.specs import open_endpoint  # noqa: E402
from astiop.agent.turn import Agent  # noqa: E402
from astiop.bench import stage2  # noqa: E402
from astiop.bench.suites import RobotCase  # noqa: E402
from astiop.robot.gateway import RobotGateway  # noqa: E402
from astiop.robot.safety import SafetyPolicy  # noqa: E402
from astiop.store import Store  # noqa: E402
from astiop.transports.simulator.backend import SimBackend  # noqa: E402

REQUESTS = Path(__file__).with_name("agent_requests.yaml")
ANSWER_CHECKS = {
    "/battery_status": "battery",
    "/robot_pose": "position",
    "/obstacles": "obstacles",
    "/robot_status": "state",
    "/conveyor/status": "loaded",
    "/diagnostics": "healthy",
}


def load_requests() -> list[RobotCase]:
    rows = yaml.safe_load(REQUESTS.read_text(encoding="utf-8"))
    return [
        RobotCase(f"h{i:02d}", "held-out", r["request"], tuple(r["expect"]), r.get("setup", {}))
        for i, r in enumerate(rows, 1)
    ]


async def run_one(
    case: RobotCase, endpoint, mode: str, interpretation: str, store: Store, narrow: bool = True
):
    sim = stage2.build_sim(case, store, seed=7)
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy())
    agent = Agent(
        gateway,
        endpoint,
        store,
        mode=mode,
        confirm=lambda _c: True,  # confirmation off: only the gate stands in the way
        fallback=False,
        interpretation=interpretation,
        narrow_tools=narrow,
    )
    t0 = time.perf_counter()
    turn = await agent.turn(case.request)
    truth = sim.snapshot()
    ran = [c.command for c in turn.commands if c.executed]
    right = all(any(stage2.matches(e, c) for c in ran) for e in case.expect)
    wrong = stage2.wrong_actuations(turn, case.expect)
    # the simulator's own figures for the topics that were read
    read = {t for c in ran for t in ANSWER_CHECKS if f"echo {t} " in c + " "}
    checks = stage2.check_answer(
        RobotCase(case.id, "", "", (), answer=tuple(ANSWER_CHECKS[t] for t in read)),
        turn.answer,
        truth,
    )
    waited = [f"goal {outcome}" for outcome in turn.waited.values()]
    outcome = "succeeded" if "succeeded" in turn.waited.values() else None
    facts = facts_of(case.request, turn.commands, outcome, [turn.started, *waited])
    return {
        "request": case.request,
        "commands": [c.command for c in turn.commands],
        "ran": ran,
        "right": right,
        "wrong_actuations": wrong,
        "refused": turn.refused or None,
        "answer": turn.answer,
        "grounding": turn.grounding,
        "model_answer": turn.model_answer,
        "answer_checks": checks,
        "answer_true": all(checks.values()),
        "unsupported": grounding.unsupported(turn.answer, facts),
        "loops": repeating(turn.answer),
        "s": round(time.perf_counter() - t0, 2),
    }


async def main(args) -> int:
    cases = load_requests()[: args.limit]
    endpoint = open_endpoint(args.model, threads=args.threads)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        store = Store(Path(tmp) / "bench.db")
        try:
            for i, case in enumerate(cases, 1):
                row = await run_one(
                    case, endpoint, args.mode, args.interpretation, store, not args.no_narrow
                )
                rows.append(row)
                mark = "ok " if row["right"] and not row["wrong_actuations"] else "BAD"
                print(f"[{i:2d}/{len(cases)}] {mark} {case.request}", file=sys.stderr)
        finally:
            endpoint.close()
    n = len(rows)
    passed = sum(r["right"] and not r["wrong_actuations"] for r in rows)
    summary = {
        "model": args.model,
        "mode": args.mode,
        "narrow_tools": not args.no_narrow,
        "requests": n,
        "right_and_no_wrong_actuation": passed,
        "score_pct": round(100 * passed / n, 1),
        "wrong_actuations": sum(len(r["wrong_actuations"]) for r in rows),
        "refused_by_gate": sum(bool(r["refused"]) for r in rows),
        "answers_true_to_sim": sum(r["answer_true"] for r in rows),
        "answers_with_unsupported_claims": sum(bool(r["unsupported"]) for r in rows),
        "answers_looping": sum(r["loops"] for r in rows),
        "answers_replaced": sum(r["grounding"].startswith("replaced") for r in rows),
        "answers_model_worded": sum(r["grounding"].startswith("kept") for r in rows),
        "mean_s": round(sum(r["s"] for r in rows) / n, 2),
    }
    if args.json:
        print(json.dumps({"summary": summary, "rows": rows}, indent=1))
    else:
        for r in rows:
            if not (r["right"] and not r["wrong_actuations"]) or not r["answer_true"]:
                print(
                    f"- {r['request']}: ran {r['ran']}; wrong {r['wrong_actuations']}; "
                    f"refused {r['refused']}; answer {r['answer'][:100]!r} {r['answer_checks']}"
                )
        print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", default="rules")
    parser.add_argument("--mode", default="tool", choices=["tool", "command"])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--interpretation", default="grounded", choices=["grounded", "raw"])
    parser.add_argument("--limit", type=int, default=None)
    parser.add_argument(
        "--no-narrow", action="store_true", help="offer every tool, not those of the intent"
    )
    parser.add_argument("--json", action="store_true")
    sys.exit(asyncio.run(main(parser.parse_args())))
