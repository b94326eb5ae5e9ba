"""Grid search of strategy parameters against human sequences (thesis 3.3.2, Table 3.4).

For `opm`, `nearest`, `opm-2step` and `optimal` under the teacher-forced APE, every
step's outcome depends only on that step (the 2-step model's second choice on the item
observed before it, `optimal` re-plans at each step), so a whole parameter grid is
scored at once: per episode and step the costs of all grid points form one
(configs x items) array, and only steps whose lowest cost is tied need random draws,
which are shared by all grid points (common random numbers, the same draws `evaluate`
uses). Other strategies and metrics are scored point by point, over worker processes.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.evaluation.evaluate import episode_rng, score_episode, strategy_factory
from cramlite.evaluation.metrics import ape_uniforms, sampled_errors
from cramlite.evaluation.options import DEFAULT_TEMPERATURE
from cramlite.evaluation.protocol import ape_steps
from cramlite.strategies.base import StrategyCrashed, StrategyError
from cramlite.strategies.cost import DIMS
from cramlite.strategies.opm import NearestStrategy, OPMStrategy, OPMTwoStepStrategy
from cramlite.strategies.optimal import TIE_RTOL, OptimalStrategy
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
        """(dims, config index) of the lowest mean error. Where several grid points fit
        exactly as well (a plateau: values that change no decision in these episodes),
        the one nearest the plateau's middle: any of them is as good a fit, and the
        middle is nearest the generating value in the worst case (in parameter recovery
        it recovers c in 93 % of fits where the first in grid order recovers 75 %)."""
        candidates = [dims] if dims else self.dims
        return min(((d, self._middle_of_best(d)) for d in candidates),
                   key=lambda t: self.means(t[0])[t[1]])

    def _tied(self, dims: str) -> np.ndarray:
        means = self.means(dims)
        return np.flatnonzero(np.isclose(means, np.nanmin(means), rtol=0.0, atol=1e-9))

    def _middle_of_best(self, dims: str) -> int:
        tied = self._tied(dims)
        points = self.configs[tied]
        distance = ((points - points.mean(axis=0)) ** 2).sum(axis=1)
        return int(tied[int(np.argmin(distance))])  # (first in grid order among equals)

    def params(self, index: int) -> dict[str, float]:
        return dict(zip(PARAM_NAMES, map(float, self.configs[index]), strict=True))

    def tied_best(self, dims: str) -> dict[str, tuple[float, float]]:
        """Each parameter's range over the grid points that fit exactly as well as the
        best one (a plateau): where a parameter changes no decision in these episodes,
        the fit cannot tell its values apart, and `best` is merely the first of them."""
        tied = self.configs[self._tied(dims)]
        return {name: (float(tied[:, j].min()), float(tied[:, j].max()))
                for j, name in enumerate(PARAM_NAMES)}


#: Strategies whose teacher-forced steps are scored over the whole grid at once.
VECTORISED = {OPMStrategy: "opm", NearestStrategy: "nearest", OPMTwoStepStrategy: "2step",
              OptimalStrategy: "optimal"}


def _vector_kind(name: str, metric: str) -> str | None:
    cls = strategy_class(name)
    return VECTORISED.get(cls) if metric in ("ape", "expected-ape", "likelihood") else None


def _cost(d: np.ndarray, k: np.ndarray, c: np.ndarray, form: str) -> np.ndarray:
    if form == "power":
        return np.power(d, k) * c
    if form == "additive":
        return d - k + c
    return d * k * c


def _grid_costs(episode: Episode, configs: np.ndarray, dims: str, form: str,
                kind: str, protocol: str) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """For each teacher-forced step: the cost of every offered item at every grid point
    (G x items; for `optimal` relative to the trip's end) and which items are the observed
    one (items,)."""
    axes = list(DIMS[dims])
    steps = ape_steps(episode, protocol)
    g = len(configs)
    for i, step in enumerate(steps):
        items = step.candidates
        positions = np.array([c.position for c in items], dtype=float)[:, axes]
        k = np.ones((g, len(items)))
        c = np.ones((g, len(items)))
        if kind != "nearest":
            category = np.array([it.category for it in items])
            for col, cat in enumerate(("strong", "mid", "food")):
                k[:, category == cat] = configs[:, col:col + 1]
            c[:, np.array([it.contained for it in items], dtype=bool)] = configs[:, 3:4]

        def costs(point: Sequence[float], k=k, c=c, positions=positions) -> np.ndarray:
            diff = positions - np.asarray(point, dtype=float)[axes]
            return _cost(np.sqrt((diff * diff).sum(axis=1))[None, :], k, c, form)

        agent: Sequence[float] = step.agent
        if kind == "2step" and i % 2 == 1:
            previous = steps[i - 1]
            agent = previous.candidates[previous.observed].fetch_position()
        cost = costs(agent)
        if kind == "optimal":
            afters = {it.after_position() for it in items}
            if len(afters) != 1:
                raise ValueError("the vectorised optimal fit needs one after-position per step")
            cost = cost - costs(afters.pop())
        yield cost, np.array([it.name == step.observed_name for it in items])


def grid_probabilities(episode: Episode, configs: np.ndarray, dims: str, form: str,
                       kind: str = "opm", protocol: str = "heldout") -> np.ndarray:
    """P(correct) per scored step and grid point, (steps, G), for the teacher-forced
    steps of `opm`, `nearest`, `opm-2step` (the second of a pair is seen from where the
    observed first item was taken) and `optimal` (the first item of a least-cost order
    when every trip starts from one point: argmin C(agent, j) - C(T, j))."""
    rows = []
    for cost, observed in _grid_costs(episode, configs, dims, form, kind, protocol):
        if kind == "optimal":
            best = cost.min(axis=1, keepdims=True)
            tied = cost <= best + TIE_RTOL * np.maximum(np.abs(best), 1.0)
        else:
            tied = cost == cost.min(axis=1, keepdims=True)
        rows.append(tied[:, observed].sum(axis=1) / tied.sum(axis=1))
    return np.array(rows).reshape(-1, len(configs))


#: The lowest temperature the likelihood is computed at: a cost difference over it stays
#: a finite number (at 1e-308 and below it overflows, and every score is infinite).
MIN_TEMPERATURE = 1e-6


def grid_nll(episode: Episode, configs: np.ndarray, dims: str, form: str,
             kind: str = "opm", protocol: str = "heldout",
             temperature: float = DEFAULT_TEMPERATURE) -> np.ndarray:
    """Negative log-likelihood (nats) of each teacher-forced step's observed choice at
    every grid point, (steps, G), under the softmax choice rule `simulate` draws with:
    P(item) proportional to exp(-cost / temperature) (an item named twice: either)."""
    if not math.isfinite(temperature) or temperature < MIN_TEMPERATURE:
        raise ValueError(f"the likelihood needs a temperature >= {MIN_TEMPERATURE:g}, got "
                         f"{temperature}")
    rows = []
    for cost, observed in _grid_costs(episode, configs, dims, form, kind, protocol):
        z = -(cost - cost.min(axis=1, keepdims=True)) / temperature  # (the best: 0)
        rows.append(_log_sum_exp(z) - _log_sum_exp(z[:, observed]))
    return np.array(rows).reshape(-1, len(configs))


def _log_sum_exp(z: np.ndarray) -> np.ndarray:
    """log(sum(exp(z))) along each row, without underflow (a choice far costlier than the
    best has a tiny, not a zero, probability)."""
    top = z.max(axis=1, keepdims=True)
    return top[:, 0] + np.log(np.exp(z - top).sum(axis=1))


def _vector_scores(episodes: Sequence[Episode], configs: np.ndarray, dims: str, form: str,
                   kind: str, metric: str, repeats: int, seed: int, protocol: str,
                   progress: Callable[[float], None] | None,
                   temperature: float = DEFAULT_TEMPERATURE) -> np.ndarray:
    table = np.zeros((len(episodes), len(configs)))
    for e, episode in enumerate(episodes):
        if len(episode) >= 2 and metric == "likelihood":
            table[e] = grid_nll(episode, configs, dims, form, kind, protocol,
                                temperature).sum(axis=0)
        elif len(episode) >= 2:
            probs = grid_probabilities(episode, configs, dims, form, kind, protocol)
            if metric == "expected-ape":
                table[e] = (1.0 - probs).sum(axis=0)
            else:
                uniforms = ape_uniforms(episode_rng(seed, e), repeats, len(probs))
                table[e] = np.median(sampled_errors(probs, uniforms), axis=0)
        if progress:
            progress(1)
    return table


def _score_points(task: tuple) -> np.ndarray:
    """Worker: score grid points one by one (strategies the grid path does not cover)."""
    episodes, strategy, rows, dims, form, metric, repeats, seed, protocol = task
    table = np.zeros((len(episodes), len(rows)))
    for g, row in enumerate(rows):
        make = strategy_factory(strategy, dict(zip(PARAM_NAMES, row, strict=True)), dims, form)
        for e, episode in enumerate(episodes):
            try:
                table[e, g] = score_episode(make, episode, metric, repeats,
                                            episode_rng(seed, e), protocol)
            except StrategyCrashed:
                raise  # a bug in the strategy: every point would fail the same way
            except StrategyError:  # e.g. too many items for `optimal`
                table[e, g] = np.nan
    return table


def _pointwise_scores(episodes: Sequence[Episode], strategy: str, configs: np.ndarray,
                      dims: str, form: str, metric: str, repeats: int, seed: int,
                      protocol: str, workers: int,
                      progress: Callable[[float], None] | None) -> np.ndarray:
    chunk = max(1, min(16, len(configs) // max(1, 4 * workers)))
    tasks = [(list(episodes), strategy, configs[i:i + chunk], dims, form, metric, repeats,
              seed, protocol) for i in range(0, len(configs), chunk)]
    parts: list[np.ndarray] = []
    if workers <= 1 or len(tasks) == 1:
        for task in tasks:
            parts.append(_score_points(task))
            if progress:
                progress(len(episodes) * len(task[2]) / len(configs))
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
            for task, part in zip(tasks, pool.map(_score_points, tasks), strict=True):
                parts.append(part)
                if progress:
                    progress(len(episodes) * len(task[2]) / len(configs))
    return np.hstack(parts)


def fit(episodes: Sequence[Episode], strategy: str = "opm", dims: Sequence[str] = ("xy",),
        metric: str = "ape", repeats: int = 100, seed: int = 0, form: str = "power",
        configs: np.ndarray | None = None,
        progress: Callable[[float], None] | None = None, protocol: str = "heldout",
        workers: int = 1, temperature: float = DEFAULT_TEMPERATURE) -> FitResult:
    """Score every grid point for each projection; scores are per episode.

    `opm`, `nearest`, `opm-2step` and `optimal` under the APE metrics are scored for the
    whole grid at once (per step, one configs x items array); other strategies and
    metrics point by point, over `workers` processes. Either way the numbers are those
    `evaluate` gives for the same seed. `progress` receives episodes done per projection.
    `likelihood` (those four strategies only): each episode's negative log-likelihood of
    the observed choices under a softmax over the costs at `temperature`; its minimum is
    the maximum-likelihood fit (the rule `simulate` draws with).
    """
    configs = source_grid() if configs is None else configs
    cls = strategy_class(strategy)
    if cls is NearestStrategy or not getattr(cls, "uses_params", True):
        configs = configs[:1]
    kind = _vector_kind(strategy, metric)
    if metric == "likelihood" and kind is None:
        raise ValueError(f"the likelihood metric needs a strategy with a cost per item "
                         f"(opm, nearest, opm-2step, optimal), got {strategy!r}")
    scores: dict[str, np.ndarray] = {}
    for dim in dims:
        if kind is not None:
            scores[dim] = _vector_scores(episodes, configs, dim, form, kind, metric, repeats,
                                         seed, protocol, progress, temperature)
        else:
            scores[dim] = _pointwise_scores(episodes, strategy, configs, dim, form, metric,
                                            repeats, seed, protocol, workers, progress)
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
