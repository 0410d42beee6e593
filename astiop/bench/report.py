"""Rankings (Table 8), breakdowns by level and category (Fig. 9), components (Figs. 12-15)."""

from __future__ import annotations

import csv
import io
import json
import statistics
from collections import defaultdict
from dataclasses import dataclass, field
from typing import Any

from astiop.bench import scoring
from astiop.bench.runner import BenchError
from astiop.store import Store


@dataclass
class ModelResult:
    model: str
    mode: str
    components: dict[str, float]
    composite: float
    cases: int
    errors: int
    timeouts: int
    by_category: dict[str, float] = field(default_factory=dict)
    by_level: dict[str, float] = field(default_factory=dict)
    by_case: dict[str, float] = field(default_factory=dict)  # stage 2: over its paraphrases

    def as_json(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "mode": self.mode,
            "components": {k: round(v, 2) for k, v in self.components.items()},
            "composite": round(self.composite, 2),
            "cases": self.cases,
            "errors": self.errors,
            "timeouts": self.timeouts,
            "by_category": {k: round(v, 1) for k, v in self.by_category.items()},
            "by_level": {k: round(v, 1) for k, v in self.by_level.items()},
            "by_case": {k: round(v, 1) for k, v in self.by_case.items()},
        }


@dataclass
class Report:
    run_id: int
    stage: int
    status: str
    wall_s: float | None
    results: list[ModelResult]
    rows: list[dict[str, Any]]

    def as_json(self) -> dict[str, Any]:
        return {
            "run_id": self.run_id,
            "stage": self.stage,
            "status": self.status,
            "wall_s": self.wall_s,
            "results": [r.as_json() for r in self.results],
        }


def _mean(values) -> float:
    values = list(values)
    return statistics.fmean(values) if values else 0.0


def load_report(store: Store, run_id: int) -> Report:
    run = store.bench_run(run_id)
    if run is None:
        raise BenchError(f"there is no benchmark run {run_id} (astiop bench list shows them)")
    rows = [dict(r, metrics=json.loads(r["metrics"])) for r in store.bench_results(run_id)]
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        groups[(r["model"], r["mode"])].append(r)
    results = _stage1(groups) if run["stage"] == 1 else _stage2(groups, rows)
    results.sort(key=lambda r: r.composite, reverse=True)
    wall = run["finished_at"] - run["started_at"] if run["finished_at"] else None
    return Report(run_id, run["stage"], run["status"], wall, results, rows)


def _breakdown(rows: list[dict], key, value) -> dict[str, float]:
    by: dict[str, list[float]] = defaultdict(list)
    for r in rows:
        by[key(r) if callable(key) else r[key]].append(value(r))
    return {k: _mean(v) for k, v in sorted(by.items())}


def _stage1(groups) -> list[ModelResult]:
    tps = {
        g: _mean(r["metrics"]["tps"] for r in rows if r["outcome"] == "ok")
        for g, rows in groups.items()
    }
    speed = scoring.speed_scores(tps)
    out = []
    for g, rows in groups.items():
        n = len(rows)
        q = _mean(r["metrics"]["q"] for r in rows)
        c = _mean(r["metrics"]["c"] for r in rows)
        ok = sum(r["outcome"] == "ok" for r in rows)
        rel = 100.0 * ok / n
        comps = {
            "quality": q,
            "coverage": c,
            "speed": speed[g],
            "reliability": rel,
            "tokens_per_s": tps[g],
        }
        out.append(
            ModelResult(
                g[0],
                g[1],
                comps,
                scoring.stage1_composite(q, c, speed[g], rel),
                n,
                sum(r["outcome"] == "error" for r in rows),
                sum(r["outcome"] == "timeout" for r in rows),
                _breakdown(rows, "category", lambda r: r["metrics"]["c"]),
                _breakdown(rows, "level", lambda r: r["metrics"]["q"]),
            )
        )
    return out


def _stage2(groups, all_rows) -> list[ModelResult]:
    slowest = max((r["metrics"].get("total_s") or 0.0 for r in all_rows), default=0.0)
    out = []
    for g, rows in groups.items():
        n = len(rows)
        c = _mean(r["metrics"].get("command", 0.0) for r in rows)
        i = _mean(r["metrics"].get("interpretation", 0.0) for r in rows)
        both = sum(bool(r["metrics"].get("c_valid") and r["metrics"].get("i_valid")) for r in rows)
        bv = 100.0 * both / n
        sp = scoring.stage2_speed(_mean(r["metrics"].get("total_s") or 0.0 for r in rows), slowest)
        comps = {
            "command": c,
            "interpretation": i,
            "both_valid": bv,
            "speed": sp,
            "mean_total_s": _mean(r["metrics"].get("total_s") or 0.0 for r in rows),
            # actuations a model ran that its case did not ask for; the gate's refusals
            "wrong_actuations": float(sum(r["metrics"].get("wrong_actuations", 0) for r in rows)),
            "refused": float(sum(bool(r["metrics"].get("refused")) for r in rows)),
        }

        def both_valid(r):
            return 100.0 * bool(r["metrics"].get("c_valid") and r["metrics"].get("i_valid"))

        out.append(
            ModelResult(
                g[0],
                g[1],
                comps,
                scoring.stage2_composite(c, i, bv, sp),
                n,
                sum(r["outcome"] == "error" for r in rows),
                sum(r["outcome"] == "timeout" for r in rows),
                _breakdown(rows, "category", both_valid),
                _breakdown(rows, "category", lambda r: r["metrics"].get("command", 0.0)),
                _breakdown(rows, lambda r: r["metrics"].get("base", r["case_id"]), both_valid),
            )
        )
    return out


# -- formats ------------------------------------------------------------------------------
def to_markdown(rep: Report) -> str:
    lines = [f"# Benchmark run {rep.run_id}: stage {rep.stage} ({rep.status})", ""]
    if rep.wall_s is not None:
        lines += [f"Wall time: {rep.wall_s:.1f} s", ""]
    if not rep.results:
        return "\n".join(lines + ["No results yet."]) + "\n"
    comp_names = [k for k in rep.results[0].components if k not in ("tokens_per_s", "mean_total_s")]
    extra = "tokens/s" if rep.stage == 1 else "mean s"
    lines += [
        "| rank | model | mode | " + " | ".join(comp_names) + f" | {extra} | composite |"
        " cases | errors | timeouts |",
        "|---" * (len(comp_names) + 8) + "|",
    ]
    for rank, r in enumerate(rep.results, 1):
        xs = r.components.get("tokens_per_s", r.components.get("mean_total_s", 0.0))
        lines.append(
            f"| {rank} | {r.model} | {r.mode} | "
            + " | ".join(f"{r.components[k]:.1f}" for k in comp_names)
            + f" | {xs:.1f} | **{r.composite:.1f}** | {r.cases} | {r.errors} |"
            f" {r.timeouts} |"
        )
    what = "coverage" if rep.stage == 1 else "both-valid rate"
    lines += ["", f"## By category ({what}, 0-100)", ""]
    lines += _matrix(rep.results, "by_category")
    what = "quality" if rep.stage == 1 else "command score"
    lines += ["", f"## By {'level' if rep.stage == 1 else 'category'} ({what}, 0-100)", ""]
    lines += _matrix(rep.results, "by_level")
    if rep.stage == 2:
        lines += ["", "## By case (both-valid over the request and its paraphrases, 0-100)", ""]
        lines += _matrix(rep.results, "by_case")
    return "\n".join(lines) + "\n"


def _matrix(results: list[ModelResult], attr: str) -> list[str]:
    keys = sorted({k for r in results for k in getattr(r, attr)})
    lines = ["| model | mode | " + " | ".join(keys) + " |", "|---" * (len(keys) + 2) + "|"]
    for r in results:
        cells = [f"{getattr(r, attr).get(k, 0.0):.0f}" for k in keys]
        lines.append(f"| {r.model} | {r.mode} | " + " | ".join(cells) + " |")
    return lines


def to_csv(rep: Report) -> str:
    buf = io.StringIO()
    keys = sorted(
        {
            k
            for r in rep.rows
            for k, v in r["metrics"].items()
            if isinstance(v, (int, float, bool, type(None)))
        }
    )
    writer = csv.writer(buf)
    writer.writerow(["model", "mode", "case_id", "level", "category", "outcome", *keys])
    for r in rep.rows:
        writer.writerow(
            [
                r["model"],
                r["mode"],
                r["case_id"],
                r["level"],
                r["category"],
                r["outcome"],
                *[r["metrics"].get(k) for k in keys],
            ]
        )
    return buf.getvalue()


def list_runs(store: Store) -> list[dict[str, Any]]:
    return [
        dict(r, models=json.loads(r["models"]), modes=json.loads(r["modes"]))
        for r in store.bench_runs()
    ]
