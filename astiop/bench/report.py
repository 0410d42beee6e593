"""Rankings (Table 8), breakdowns by level and category (Fig. 9), components (Figs. 12-15)."""

from __future__ import annotations

import csv
import io
import json
import statistics
from collections import defaultdict
from dataclasses import dataclass, field
from typing import Any

from astiop.bench import questions, scoring
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
    protocol: str = "astiop"
    suite: str = ""

    def as_json(self) -> dict[str, Any]:
        return {
            "run_id": self.run_id,
            "stage": self.stage,
            "status": self.status,
            "protocol": self.protocol,
            "suite": self.suite,
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
    config = json.loads(run["config"] or "{}")
    results = []
    for paper in (False, True):  # each protocol is normalised within itself
        groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
        for r in rows:
            if (r["mode"] == "paper") == paper:
                groups[(r["model"], r["mode"])].append(r)
        if groups:
            part = _stage1(groups, paper) if run["stage"] == 1 else _stage2(groups)
            results += sorted(part, key=lambda r: r.composite, reverse=True)
    wall = run["finished_at"] - run["started_at"] if run["finished_at"] else None
    rep = Report(run_id, run["stage"], run["status"], wall, results, rows)
    rep.protocol = config.get("protocol", "astiop")
    rep.suite = config.get("suite") or f"astiop-stage{run['stage']}"
    return rep


def _breakdown(rows: list[dict], key, value) -> dict[str, float]:
    by: dict[str, list[float]] = defaultdict(list)
    for r in rows:
        by[key(r) if callable(key) else r[key]].append(value(r))
    return {k: _mean(v) for k, v in sorted(by.items())}


def _stage1(groups, paper: bool = False) -> list[ModelResult]:
    if paper:  # Eq. 2 as the paper's Table 8 reads: every test counts, failures as 0
        tps = {g: _mean(r["metrics"]["tps"] for r in rows) for g, rows in groups.items()}
        fastest_case = max((r["metrics"]["tps"] for rs in groups.values() for r in rs), default=0)
        speed = {g: scoring.paper_speed(v, fastest_case) for g, v in tps.items()}
    else:
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
            "mean_total_s": _mean(r["metrics"].get("total_s") or 0.0 for r in rows),
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
                _breakdown(rows, "category", lambda r: r["metrics"]["q"]),  # Fig. 9
                _breakdown(rows, "level", lambda r: r["metrics"]["q"]),
            )
        )
    return out


def _stage2(groups) -> list[ModelResult]:
    # a case a live robot cannot be set up for is not scored (its row says why)
    groups = {g: [r for r in rows if r["outcome"] != "skipped"] for g, rows in groups.items()}
    groups = {g: rows for g, rows in groups.items() if rows}
    slowest = max(
        (r["metrics"].get("total_s") or 0.0 for rows in groups.values() for r in rows), default=0.0
    )
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
            "command_valid_rate": 100.0 * sum(bool(r["metrics"].get("c_valid")) for r in rows) / n,
            "interpretation_valid_rate": 100.0
            * sum(bool(r["metrics"].get("i_valid")) for r in rows)
            / n,
            # actuations a model ran that its case did not ask for; the gate's refusals
            "wrong_actuations": float(sum(r["metrics"].get("wrong_actuations", 0) for r in rows)),
            "refused": float(sum(bool(r["metrics"].get("refused")) for r in rows)),
        }
        verdicts = [r["metrics"]["verdict"] for r in rows if "verdict" in r["metrics"]]
        if verdicts:  # the questions suite: right / honestly declined / answered something else
            comps |= {f"questions_{k}": float(v) for k, v in questions.tally(verdicts).items()}

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
SIDE_FIGURES = ("tokens_per_s", "mean_total_s", "command_valid_rate", "interpretation_valid_rate")
TABLE8 = {
    1: (("quality", "Quality"), ("coverage", "Coverage"), ("speed", "Speed"),
        ("reliability", "Reliability")),
    2: (("command", "Command"), ("interpretation", "Interpretation"),
        ("both_valid", "Both valid"), ("speed", "Speed")),
}  # fmt: skip


def _protocol(r: ModelResult) -> str:
    return "paper" if r.mode == "paper" else "astiop"


def to_markdown(rep: Report, cases: bool = True) -> str:
    lines = [f"# Benchmark run {rep.run_id}: stage {rep.stage} ({rep.status})", ""]
    lines += [f"Suite: {rep.suite}. Protocol: {rep.protocol}.", ""]
    if rep.wall_s is not None:
        lines += [f"Wall time: {rep.wall_s:.1f} s", ""]
    if not rep.results:
        return "\n".join(lines + ["No results yet."]) + "\n"
    for protocol in ("astiop", "paper"):
        results = [r for r in rep.results if _protocol(r) == protocol]
        if results:
            lines += _ranking(rep.stage, protocol, results)
    what = "quality" if rep.stage == 1 else "both-valid rate"
    lines += ["", f"## By category ({what}, 0-100)", ""]
    lines += _matrix(rep.results, "by_category")
    what = "quality" if rep.stage == 1 else "command score"
    lines += ["", f"## By {'level' if rep.stage == 1 else 'category'} ({what}, 0-100)", ""]
    lines += _matrix(rep.results, "by_level")
    if rep.stage == 2 and any(_protocol(r) == "astiop" for r in rep.results):
        lines += ["", "## By case (both-valid over the request and its paraphrases, 0-100)", ""]
        lines += _matrix([r for r in rep.results if _protocol(r) == "astiop"], "by_case")
    if cases:
        lines += ["", "## Every case", ""] + _cases_table(rep)
    return "\n".join(lines) + "\n"


def _ranking(stage: int, protocol: str, results: list[ModelResult]) -> list[str]:
    """Table 8's shape: rank, model, the composite's components, the composite."""
    cols = TABLE8[stage]
    eq = "Eq. 1" if stage == 1 else "Eq. 9"
    title = "the paper's protocol" if protocol == "paper" else "astiop's protocol"
    extra = "Tokens/s" if stage == 1 else "Mean s"
    lines = [
        f"## Ranking, {title} ({eq})",
        "",
        "| Rank | Model | Mode | "
        + " | ".join(name for _, name in cols)
        + f" | Composite | {extra} | Cases | Errors | Timeouts |",
        "|---" * (len(cols) + 8) + "|",
    ]
    for rank, r in enumerate(results, 1):
        xs = r.components.get("tokens_per_s" if stage == 1 else "mean_total_s", 0.0)
        lines.append(
            f"| {rank} | {r.model} | {r.mode} | "
            + " | ".join(f"{r.components[k]:.2f}" for k, _ in cols)
            + f" | **{r.composite:.2f}** | {xs:.2f} | {r.cases} | {r.errors} | {r.timeouts} |"
        )
    if stage == 2 and protocol == "astiop":
        wrong = {r.model: r.components.get("wrong_actuations", 0) for r in results}
        lines += ["", "Wrong actuations: " + ", ".join(f"{m} {v:.0f}" for m, v in wrong.items())]
        asked = [r for r in results if "questions_right" in r.components]
        if asked:
            lines += [
                "",
                "Questions (right / honestly declined / answered something else): "
                + ", ".join(
                    f"{r.model} {r.components['questions_right']:.0f} / "
                    f"{r.components['questions_declined']:.0f} / "
                    f"{r.components['questions_other']:.0f}"
                    for r in asked
                ),
            ]
    return lines + [""]


def _matrix(results: list[ModelResult], attr: str) -> list[str]:
    keys = sorted({k for r in results for k in getattr(r, attr)})
    lines = ["| model | mode | " + " | ".join(keys) + " |", "|---" * (len(keys) + 2) + "|"]
    for r in results:
        cells = [f"{getattr(r, attr).get(k, 0.0):.0f}" for k in keys]
        lines.append(f"| {r.model} | {r.mode} | " + " | ".join(cells) + " |")
    return lines


def _cell(text: Any, width: int = 60) -> str:
    flat = " ".join(str(text or "").split()).replace("|", "\\|")
    return flat if len(flat) <= width else flat[: width - 1] + "…"


def _cases_table(rep: Report) -> list[str]:
    if rep.stage == 1:
        head = "| model | mode | case | category | outcome | quality | coverage | tokens/s | s | response |"
        fields = ("q", "c", "tps", "total_s")
    else:
        head = "| model | mode | case | category | outcome | command | interpretation | both valid | s | response |"
        fields = ("command", "interpretation", None, "total_s")
    lines = [head, "|---" * 10 + "|"]
    for row in rep.rows:
        m = row["metrics"]
        values = []
        for f in fields:
            if f is None:
                values.append("yes" if m.get("c_valid") and m.get("i_valid") else "no")
            else:
                values.append(f"{float(m.get(f) or 0.0):.2f}")
        lines.append(
            f"| {row['model']} | {row['mode']} | {row['case_id']} | {row['category']} | "
            f"{row['outcome']} | " + " | ".join(values) + f" | {_cell(row['response'])} |"
        )
    return lines


def case_rows(rep: Report) -> list[dict[str, Any]]:
    """Every case as one flat record: prompt, response text(s), expectations, every score."""
    out = []
    for row in rep.rows:
        record = {
            "run_id": rep.run_id,
            "run_stage": rep.stage,  # "stage" is the paper's own field (how far a case got)
            "timestamp": row.get("created_at"),
            "model": row["model"],
            "mode": row["mode"],
            "case_id": row["case_id"],
            "level": row["level"],
            "category": row["category"],
            "outcome": row["outcome"],
            "response": row["response"],
        }
        # a stage-2 case's outcome checks (arrive, docked, ...) beside the row's own outcome
        record.update(
            {("outcome_checks" if k == "outcome" else k): v for k, v in row["metrics"].items()}
        )
        out.append(record)
    return out


def to_json(rep: Report) -> str:
    return json.dumps({**rep.as_json(), "cases": case_rows(rep)}, indent=2, default=str)


def to_jsonl(rep: Report) -> str:
    return "".join(json.dumps(r, default=str) + "\n" for r in case_rows(rep))


def to_csv(rep: Report) -> str:
    records = case_rows(rep)
    keys: list[str] = []
    for r in records:
        keys += [k for k in r if k not in keys]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys)
    writer.writeheader()
    for r in records:
        writer.writerow(
            {k: json.dumps(v) if isinstance(v, (list, dict)) else v for k, v in r.items()}
        )
    return buf.getvalue()


def list_runs(store: Store) -> list[dict[str, Any]]:
    return [
        dict(r, models=json.loads(r["models"]), modes=json.loads(r["modes"]))
        for r in store.bench_runs()
    ]
