"""How much the watches cost: one evaluator step with N watches and the built-in alerts on a
real SQLite store, over a stream of robot states (a battery draining past the thresholds).

    python benchmarks/watches.py [--watches 100] [--robots 25] [--steps 400]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from astiop.store import Store
from astiop.transports.state import Battery, RobotState, Status
from astiop.watches.evaluator import Evaluator
from astiop.watches.model import Watch


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--watches", type=int, default=100)
    ap.add_argument("--robots", type=int, default=25)
    ap.add_argument("--steps", type=int, default=400)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        store = Store(Path(tmp) / "bench.db")
        robots = [f"astibot_{i}" for i in range(args.robots)]
        for n in range(args.watches):
            w = Watch("battery", "<", 20 + n % 60, repeat="every", robot=robots[n % len(robots)])
            store.add_watch(**w.row())
        evaluators = [Evaluator(store, r) for r in robots]
        status = Status("idle", "auto", "", "", 0.0, False, False)
        t0, cpu0 = time.perf_counter(), time.process_time()
        for step in range(args.steps):
            level = 0.9 - 0.8 * step / args.steps  # 90 % down to 10 %
            state = RobotState(step * 0.1, battery=Battery(level, 24, -1, False), status=status)
            for ev in evaluators:
                ev.step(state, now=step * 0.1)
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
        samples = args.steps * len(robots)
        alerts = len(store.list_alerts(limit=100_000))
        print(f"{args.watches} watches over {len(robots)} robots, {args.steps} samples each")
        print(f"  {cpu / samples * 1e6:.0f} us CPU per robot sample ({wall:.2f} s wall in all)")
        print(f"  at 10 Hz per robot: {cpu / samples * 10 * len(robots) * 100:.1f} % of a core")
        print(f"  {alerts} alerts written")
        store.close()


if __name__ == "__main__":
    main()
