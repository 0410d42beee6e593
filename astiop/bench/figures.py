"""The paper's figure kinds for one benchmark run, as SVG and PNG files (matplotlib, optional:
pip install "astiop[plots]").

Stage 1: per-model bars of response time, tokens/s, quality and coverage (Fig. 7), reliability
stacks (Fig. 8), quality by category (Fig. 9), radar (Fig. 10), ranking with its components
(Fig. 11). Stage 2: command, interpretation and both-valid rates (Fig. 12), reliability (Fig. 8),
command and interpretation scores by category (Fig. 13), radar (Fig. 14), ranking (Fig. 15).
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

from astiop.bench.report import Report

WEIGHTS = {
    1: (("quality", 0.35), ("coverage", 0.30), ("speed", 0.20), ("reliability", 0.15)),
    2: (("command", 0.25), ("interpretation", 0.25), ("both_valid", 0.30), ("speed", 0.20)),
}


class FiguresUnavailable(RuntimeError):
    """matplotlib is not installed."""


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        raise FiguresUnavailable(
            'figures need matplotlib: pip install "astiop[plots]" (the terminal charts need '
            "nothing)"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _label(r) -> str:
    return r.model if r.mode in ("chat", "paper") else f"{r.model} ({r.mode})"


def write_figures(rep: Report, folder: Path) -> list[Path]:
    """Every figure of the run's stage, each as .svg and .png; returns the files."""
    plt = _pyplot()
    if not rep.results:
        raise FiguresUnavailable(f"run {rep.run_id} has no results to draw")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    plt.rcParams.update(
        {"font.size": 9, "figure.dpi": 110, "svg.hashsalt": "astiop", "svg.fonttype": "none",
         "figure.constrained_layout.use": True}
    )  # fmt: skip  # SVG text stays text: searchable, and the run's numbers readable in the file
    draw = _STAGE1 if rep.stage == 1 else _STAGE2
    written = []
    for name, fn in draw:
        fig = fn(plt, rep)
        fig.suptitle(f"{fig._suptitle.get_text() if fig._suptitle else name} - run {rep.run_id}")
        for ext in ("svg", "png"):
            path = folder / f"run{rep.run_id}-{name}.{ext}"
            fig.savefig(path, metadata={"Date": None} if ext == "svg" else None)
            written.append(path)
        plt.close(fig)
    return written


def _bars(plt, rep: Report, panels: list[tuple[str, str]], title: str):
    labels = [_label(r) for r in rep.results]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 3.4), squeeze=False)
    for ax, (key, what) in zip(axes[0], panels):
        values = [r.components.get(key, 0.0) for r in rep.results]
        bars = ax.bar(range(len(labels)), values, color="#3b7dd8")
        ax.bar_label(bars, fmt="%.1f", fontsize=8)
        percent = key not in ("mean_total_s", "tokens_per_s")
        ax.set_ylim(0, 105 if percent else max(max(values, default=0) * 1.15, 1.0))
        ax.set_title(what)
        ax.set_xticks(range(len(labels)), labels, rotation=30, ha="right")
    fig.suptitle(title)
    return fig


def _reliability(plt, rep: Report):
    labels = [_label(r) for r in rep.results]
    ok = [r.cases - r.errors - r.timeouts for r in rep.results]
    err = [r.errors for r in rep.results]
    out = [r.timeouts for r in rep.results]
    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    x = range(len(labels))
    ax.bar(x, ok, label="success", color="#3aa655")
    ax.bar(x, err, bottom=ok, label="error", color="#d64545")
    ax.bar(x, out, bottom=[a + b for a, b in zip(ok, err)], label="timeout", color="#e0a030")
    ax.set_xticks(list(x), labels, rotation=30, ha="right")
    ax.set_ylabel("cases")
    ax.legend(fontsize=8)
    fig.suptitle("Reliability (Fig. 8)")
    return fig


def _by_category(rep: Report, value) -> tuple[list[str], list[list[float]]]:
    cats = sorted({row["category"] for row in rep.rows})
    grid = []
    for r in rep.results:
        sums: dict[str, list[float]] = defaultdict(list)
        for row in rep.rows:
            if (row["model"], row["mode"]) == (r.model, r.mode):
                sums[row["category"]].append(value(row["metrics"]))
        grid.append([sum(sums[c]) / len(sums[c]) if sums[c] else math.nan for c in cats])
    return cats, grid


def _heat(plt, ax, rep: Report, cats, grid, title: str):
    image = ax.imshow(grid, vmin=0, vmax=100, cmap="viridis", aspect="auto")
    ax.set_xticks(range(len(cats)), cats, rotation=35, ha="right")
    ax.set_yticks(range(len(rep.results)), [_label(r) for r in rep.results])
    for i, row in enumerate(grid):
        for j, v in enumerate(row):
            if not math.isnan(v):
                ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=8,
                        color="white" if v < 60 else "black")  # fmt: skip
    ax.set_title(title)
    return image


def _heatmaps(plt, rep: Report, panels, title: str):
    height = max(2.8, 2.4 + 0.5 * len(rep.results))
    width = max(5.5, 2.5 + 0.45 * len({row["category"] for row in rep.rows}))
    fig, axes = plt.subplots(1, len(panels), figsize=(width * len(panels), height), squeeze=False)
    image = None
    for ax, (what, value) in zip(axes[0], panels):
        cats, grid = _by_category(rep, value)
        image = _heat(plt, ax, rep, cats, grid, what)
    fig.colorbar(image, ax=list(axes[0]), shrink=0.8)
    fig.suptitle(title)
    return fig


def _radar(plt, rep: Report, title: str):
    keys = [k for k, _ in WEIGHTS[rep.stage]]
    angles = [2 * math.pi * k / len(keys) for k in range(len(keys))]
    fig = plt.figure(figsize=(4.8, 4.4))
    ax = fig.add_subplot(polar=True)
    for r in rep.results:
        values = [r.components.get(k, 0.0) for k in keys]
        ax.plot([*angles, angles[0]], [*values, values[0]], label=_label(r))
        ax.fill([*angles, angles[0]], [*values, values[0]], alpha=0.1)
    ax.set_xticks(angles, keys)
    ax.set_ylim(0, 100)
    ax.legend(fontsize=7, loc="lower right", bbox_to_anchor=(1.25, -0.1))
    fig.suptitle(title)
    return fig


def _ranking(plt, rep: Report, title: str):
    ranked = list(reversed(rep.results))  # best at the top
    labels = [_label(r) for r in ranked]
    fig, ax = plt.subplots(figsize=(6.5, max(2.6, 1.2 + 0.45 * len(ranked))))
    left = [0.0] * len(ranked)
    for key, weight in WEIGHTS[rep.stage]:
        part = [weight * r.components.get(key, 0.0) for r in ranked]
        ax.barh(labels, part, left=left, label=f"{weight:g} x {key}")
        left = [a + b for a, b in zip(left, part)]
    for y, r in enumerate(ranked):
        ax.text(left[y] + 1, y, f"{r.composite:.2f}", va="center", fontsize=8)
    ax.set_xlim(0, 105)
    ax.set_xlabel("composite score")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.3), ncol=4, frameon=False)
    fig.suptitle(title)
    return fig


_STAGE1 = [
    ("fig07-bars", lambda plt, rep: _bars(plt, rep, [
        ("mean_total_s", "response time (s)"), ("tokens_per_s", "tokens/s"),
        ("quality", "quality"), ("coverage", "coverage (%)")], "Stage 1 per model (Fig. 7)")),
    ("fig08-reliability", _reliability),
    ("fig09-quality-by-category", lambda plt, rep: _heatmaps(
        plt, rep, [("quality", lambda m: m.get("q", 0.0))], "Quality by category (Fig. 9)")),
    ("fig10-radar", lambda plt, rep: _radar(plt, rep, "Stage 1 profile (Fig. 10)")),
    ("fig11-ranking", lambda plt, rep: _ranking(plt, rep, "Stage 1 ranking, Eq. 1 (Fig. 11)")),
]  # fmt: skip
_STAGE2 = [
    ("fig12-bars", lambda plt, rep: _bars(plt, rep, [
        ("command_valid_rate", "valid commands (%)"),
        ("interpretation_valid_rate", "valid interpretations (%)"),
        ("both_valid", "both valid (%)"), ("mean_total_s", "time per task (s)")],
        "Stage 2 per model (Fig. 12)")),
    ("fig08-reliability", _reliability),
    ("fig13-by-category", lambda plt, rep: _heatmaps(plt, rep, [
        ("command score", lambda m: m.get("command", 0.0)),
        ("interpretation score", lambda m: m.get("interpretation", 0.0))],
        "Command and interpretation by category (Fig. 13)")),
    ("fig14-radar", lambda plt, rep: _radar(plt, rep, "Stage 2 profile (Fig. 14)")),
    ("fig15-ranking", lambda plt, rep: _ranking(plt, rep, "Stage 2 ranking, Eq. 9 (Fig. 15)")),
]  # fmt: skip
