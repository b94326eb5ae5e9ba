"""`cramlite compare`: several strategies on the same episodes, paired Wilcoxon signed-rank
tests against the first (scipy), and the thesis's Figure 3.18 (per-episode error
distributions side by side) as a PNG.

Under `heldout`, a learned model trained on this very file is scored on its test split
only, so every strategy is scored on the episodes all of them can be scored on (the
intersection), which keeps the tests paired.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.evaluation.evaluate import Evaluation, evaluate


def compare(episodes: Sequence[Episode], strategies: Sequence[str], metric: str = "ape",
            protocol: str = "heldout", repeats: int = 100, seed: int = 0,
            data_sha256: str | None = None,
            progress: Callable[[int], None] | None = None) -> dict[str, Any]:
    results: dict[str, Evaluation] = {}
    for name in strategies:
        results[name] = evaluate(episodes, name, metric=metric, repeats=repeats, seed=seed,
                                 protocol=protocol, data_sha256=data_sha256,
                                 progress=progress)
    common = set.intersection(*({ep.id for ep in r.episodes} for r in results.values()))
    order = [ep.id for ep in episodes if ep.id in common]
    table = {name: _column(r, order) for name, r in results.items()}
    first = strategies[0]
    summary: dict[str, Any] = {
        "metric": metric, "protocol": protocol, "repeats": repeats, "seed": seed,
        "episodes": len(order),
        "strategies": {name: {"mean": float(np.mean(v)) if len(v) else None,
                              "median": float(np.median(v)) if len(v) else None,
                              "score_kind": results[name].score_kind,
                              "scored": results[name].settings.get("scored", "all episodes")}
                       for name, v in table.items()},
        "wilcoxon_vs_first": {name: _wilcoxon(table[first], table[name])
                              for name in strategies[1:]},
        "per_episode": [{"id": i, **{n: float(table[n][k]) for n in strategies}}
                        for k, i in enumerate(order)],
    }
    return {"summary": summary, "table": table}


def _column(result: Evaluation, order: Sequence[str]) -> np.ndarray:
    by_id = {ep.id: s for ep, s in zip(result.episodes, result.scores, strict=True)}
    return np.array([by_id[i] for i in order], dtype=float)


def _wilcoxon(a: np.ndarray, b: np.ndarray) -> dict[str, Any]:
    from scipy import stats

    if len(a) == 0 or not np.any(a - b):
        return {"statistic": None, "p": 1.0, "note": "identical scores"}
    res = stats.wilcoxon(a, b)
    return {"statistic": float(res.statistic), "p": float(res.pvalue)}


def plot_distributions(table: dict[str, np.ndarray], metric: str, title: str,
                       path: Path) -> bool:
    """Figure 3.18: violins of the per-episode errors, quartile lines, means marked."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    names = list(table)
    data = [table[n] if len(table[n]) else np.zeros(1) for n in names]
    fig, ax = plt.subplots(figsize=(1.9 * len(names) + 2.5, 4.5))
    ax.violinplot(data, showextrema=False)
    for i, values in enumerate(data, start=1):
        q1, q2, q3 = np.percentile(values, [25, 50, 75])
        ax.hlines([q1, q3], i - 0.15, i + 0.15, color="black", linewidth=1)
        ax.hlines(q2, i - 0.25, i + 0.25, color="black", linewidth=2)
        ax.plot(i, np.mean(values), "o", color="white", markeredgecolor="black")
    labels = [f"{_short(n)}\nmean {np.mean(v):.2f}" for n, v in zip(names, data, strict=True)]
    ax.set_xticks(range(1, len(names) + 1), labels)
    ax.set_ylabel(f"{metric} per episode")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _short(name: str) -> str:
    return f"learned:{Path(name[8:]).name}" if name.startswith("learned:") else name
