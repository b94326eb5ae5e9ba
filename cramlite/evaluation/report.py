"""Writing fit results: the error surface (CSV), a summary (JSON) and a plot (PNG)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.evaluation.fit import PARAM_NAMES, SOURCE_BEST, FitResult, paired_tests


def fit_summary(result: FitResult, baselines: list[float]) -> dict[str, Any]:
    """Each projection's best grid point and scores. A strategy that takes no parameters
    (random, nearest, a plugin that says so) is scored once a projection, with no
    parameters to report (not the first grid point's, which it ignored)."""
    takes_params = _takes_params(result)
    per_dims = {}
    samples = {}
    for dims in result.dims:
        _, index = result.best(dims)
        column = result.scores[dims][:, index]
        samples[dims] = column
        per_dims[dims] = {"params": result.params(index) if takes_params else {},
                          "mean": float(np.nanmean(column)),
                          "median": float(np.nanmedian(column)),
                          "episodes": int(np.isfinite(column).sum()),
                          "tied_best": {name: list(span) for name, span
                                        in result.tied_best(dims).items()}
                          if takes_params else {}}
    best_dims, best_index = result.best()
    summary: dict[str, Any] = {
        "strategy": result.strategy, "metric": result.metric, "grid_points": len(result.configs),
        "best": {"dims": best_dims, **per_dims[best_dims]}, "by_projection": per_dims,
        "random_baseline_mean": float(np.mean(baselines)) if baselines else None,
        "tests_between_projections": paired_tests(samples) if len(samples) > 1 else {},
    }
    source = np.flatnonzero(np.all(np.isclose(result.configs, SOURCE_BEST), axis=1))
    if len(source) and len(result.configs) > 1:
        column = result.scores[best_dims][:, source[0]]
        summary["source_params"] = {
            "params": dict(zip(PARAM_NAMES, SOURCE_BEST, strict=True)), "dims": best_dims,
            "mean": float(np.nanmean(column)), "median": float(np.nanmedian(column)),
            "test_vs_best": paired_tests({"best": result.scores[best_dims][:, best_index],
                                          "source": column})["wilcoxon"]["best vs source"]}
    return summary


def _takes_params(result: FitResult) -> bool:
    from cramlite.strategies.registry import ignores_params

    return not ignores_params(result.strategy)


def write_surface(result: FitResult, path: Path) -> None:
    """surface.csv: each grid point's mean and median per projection (the parameter
    columns empty for a strategy that takes none)."""
    takes_params = _takes_params(result)
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["dims", *PARAM_NAMES, "mean", "median"])
        for dims in result.dims:
            table = result.scores[dims]
            means, medians = np.nanmean(table, axis=0), np.nanmedian(table, axis=0)
            for g, row in enumerate(result.configs):
                values = [f"{v:.1f}" for v in row] if takes_params else [""] * len(row)
                writer.writerow([dims, *values, f"{means[g]:.6f}", f"{medians[g]:.6f}"])


def plot_by_projection(result: FitResult, baselines: list[float], path: Path) -> bool:
    """Box plot of per-episode error at each projection's best parameters."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    columns, labels = [], []
    for dims in result.dims:
        _, index = result.best(dims)
        column = result.scores[dims][:, index]
        columns.append(column[np.isfinite(column)])
        labels.append(f"{dims}\nmean {columns[-1].mean():.2f}")
    fig, ax = plt.subplots(figsize=(1.6 * len(columns) + 3, 4.5))
    ax.boxplot(columns, tick_labels=labels, showmeans=True)
    if baselines:
        ax.axhline(float(np.mean(baselines)), color="grey", linestyle="--",
                   label=f"random baseline (mean {np.mean(baselines):.2f})")
        ax.legend(loc="upper right")
    ax.set_ylabel("negative log-likelihood per episode (nats)" if result.metric == "likelihood"
                  else f"{result.metric} per episode")
    ax.set_title(f"{result.strategy}: error by projection (best parameters of each)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def write_fit(result: FitResult, baselines: list[float], out: Path) -> dict[str, Any]:
    out.mkdir(parents=True, exist_ok=True)
    summary = fit_summary(result, baselines)
    write_surface(result, out / "surface.csv")
    summary["files"] = {"surface": str(out / "surface.csv"), "summary": str(out / "fit.json")}
    if plot_by_projection(result, baselines, out / "error_by_projection.png"):
        summary["files"]["plot"] = str(out / "error_by_projection.png")
    (out / "fit.json").write_text(json.dumps(summary, indent=2))
    return summary
