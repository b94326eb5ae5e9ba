"""Grid search of strategy parameters against human sequences (thesis 3.3.2, Table 3.4).

For the OPM family (memoryless, teacher-forced APE) every step's outcome depends only on
that step, so a whole parameter grid is scored at once: per episode and step the
distances are computed once, the costs of all grid points form one (configs x items)
array, and only steps whose lowest cost is tied need random draws, which are shared by
all grid points (common random numbers, the same draws `evaluate` uses). Other
strategies are scored point by point.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.evaluation.evaluate import episode_rng, score_episode, strategy_factory
from cramlite.evaluation.metrics import ape_uniforms, sampled_errors
from cramlite.strategies.base import StrategyError
from cramlite.strategies.cost import DIMS
from cramlite.strategies.opm import NearestStrategy, OPMStrategy
from cramlite.strategies.registry import strategy_class

PARAM_NAMES = ("strong_k", "mid_k", "food_k", "c")
SOURCE_BEST = (0.2, 0.3, 1.2, 1.7)


def _steps(lo: float, hi: float) -> list[float]:
    return [round(lo + 0.1 * i, 1) for i in range(round((hi - lo) / 0.1) + 1)]


def source_grid(independent_mid: bool = False) -> np.ndarray:
    """Table 3.4 in steps of 0.1: strong 0.0-0.9, mid = strong + 0.1 (as published) or
    0.1-1.0 independently, food 1.1-2.0, c 1.0-2.0. Rows: strong, mid, food, c."""
    strong, food, c = _steps(0.0, 0.9), _steps(1.1, 2.0), _steps(1.0, 2.0)
    if independent_mid:
        rows = itertools.product(strong, _steps(0.1, 1.0), food, c)
    else:
        rows = ((s, round(s + 0.1, 1), f, cc) for s, f, cc in itertools.product(strong, food, c))
    return np.array(list(rows), dtype=float)


@dataclass
class FitResult:
    strategy: str
    metric: str
    dims: list[str]
    configs: np.ndarray  # (G, 4)
    scores: dict[str, np.ndarray]  # dims -> (episodes, G)

    def means(self, dims: str) -> np.ndarray:
        """Mean over episodes per grid point (episodes the strategy skipped are NaN)."""
        return np.nanmean(self.scores[dims], axis=0)

    def best(self, dims: str | None = None) -> tuple[str, int]:
        """(dims, config index) of the lowest mean error (first in grid order on ties)."""
        candidates = [dims] if dims else self.dims
        return min(((d, int(np.argmin(self.means(d)))) for d in candidates),
                   key=lambda t: self.means(t[0])[t[1]])

    def params(self, index: int) -> dict[str, float]:
        return dict(zip(PARAM_NAMES, map(float, self.configs[index]), strict=True))


def _vectorisable(name: str, metric: str) -> bool:
    cls = strategy_class(name)
    return metric in ("ape", "expected-ape") and cls in (OPMStrategy, NearestStrategy)


def grid_probabilities(episode: Episode, configs: np.ndarray, dims: str, form: str,
                       ignore_params: bool = False) -> np.ndarray:
    """P(correct) per scored step and grid point: (steps, G)."""
    items = episode.sequence_items()
    positions = np.array([c.position for c in items], dtype=float)[:, list(DIMS[dims])]
    category = np.array([c.category for c in items])
    contained = np.array([c.contained for c in items])
    names = np.array(episode.sequence)
    g = len(configs)
    out = np.empty((len(episode) - 1, g))
    remaining = np.arange(len(items))
    for step in range(len(episode) - 1):
        agent = np.asarray(episode.start_positions[step], dtype=float)[list(DIMS[dims])]
        diff = positions[remaining] - agent
        d = np.sqrt((diff * diff).sum(axis=1))[None, :]
        k = np.ones((g, len(remaining)))
        c = np.ones((g, len(remaining)))
        if not ignore_params:
            for col, cat in enumerate(("strong", "mid", "food")):
                mask = category[remaining] == cat
                k[:, mask] = configs[:, col:col + 1]
            c[:, contained[remaining]] = configs[:, 3:4]
        if form == "power":
            cost = np.power(d, k) * c
        elif form == "additive":
            cost = d - k + c
        else:
            cost = d * k * c
        tied = cost == cost.min(axis=1, keepdims=True)
        hits = tied[:, names[remaining] == episode.sequence[step]].sum(axis=1)
        out[step] = hits / tied.sum(axis=1)
        remaining = remaining[remaining != step]
    return out


def fit(episodes: Sequence[Episode], strategy: str = "opm", dims: Sequence[str] = ("xy",),
        metric: str = "ape", repeats: int = 100, seed: int = 0, form: str = "power",
        configs: np.ndarray | None = None,
        progress: Callable[[int], None] | None = None) -> FitResult:
    """Score every grid point for each projection; scores are per episode."""
    configs = source_grid() if configs is None else configs
    cls = strategy_class(strategy)
    if cls is NearestStrategy or not getattr(cls, "uses_params", True):
        configs = configs[:1]
    scores: dict[str, np.ndarray] = {}
    for dim in dims:
        table = np.zeros((len(episodes), len(configs)))
        if _vectorisable(strategy, metric):
            for e, episode in enumerate(episodes):
                if len(episode) >= 2:
                    probs = grid_probabilities(episode, configs, dim, form,
                                               ignore_params=cls is NearestStrategy)
                    if metric == "expected-ape":
                        table[e] = (1.0 - probs).sum(axis=0)
                    else:
                        uniforms = ape_uniforms(episode_rng(seed, e), repeats, len(probs))
                        table[e] = np.median(sampled_errors(probs, uniforms), axis=0)
                if progress:
                    progress(1)
        else:
            for g, row in enumerate(configs):
                make = strategy_factory(strategy, dict(zip(PARAM_NAMES, row, strict=True)),
                                        dim, form)
                for e, episode in enumerate(episodes):
                    try:
                        table[e, g] = score_episode(make, episode, metric, repeats,
                                                    episode_rng(seed, e))
                    except StrategyError:  # e.g. too many items for `optimal`
                        table[e, g] = np.nan
                if progress:
                    progress(len(episodes) / len(configs))
        scores[dim] = table
    return FitResult(strategy, metric, list(dims), configs, scores)


def paired_tests(samples: dict[str, np.ndarray]) -> dict[str, Any]:
    """Wilcoxon signed-rank for each pair, Friedman across all (>= 3), from scipy."""
    from scipy import stats

    out: dict[str, Any] = {"wilcoxon": {}}
    names = list(samples)
    keep = np.all([np.isfinite(samples[n]) for n in names], axis=0)
    samples = {n: v[keep] for n, v in samples.items()}
    for a, b in itertools.combinations(names, 2):
        diff = samples[a] - samples[b]
        if not np.any(diff):
            out["wilcoxon"][f"{a} vs {b}"] = {"statistic": None, "p": 1.0,
                                              "note": "identical scores"}
            continue
        res = stats.wilcoxon(samples[a], samples[b])
        out["wilcoxon"][f"{a} vs {b}"] = {"statistic": float(res.statistic),
                                          "p": float(res.pvalue)}
    if len(names) >= 3:
        res = stats.friedmanchisquare(*(samples[n] for n in names))
        out["friedman"] = {"groups": names, "statistic": float(res.statistic),
                           "p": float(res.pvalue)}
    return out
