"""Scoring a strategy over many episodes: per-episode scores, summaries by activity."""

from __future__ import annotations

import statistics
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.evaluation.metrics import (
    expected_ape,
    random_ape,
    random_edit,
    sampled_ape,
    sampled_edit,
)
from cramlite.strategies.base import Strategy, StrategyError
from cramlite.strategies.registry import make_strategy

METRICS = ("ape", "expected-ape", "edit", "edit-unrestricted")


def episode_rng(seed: int, index: int) -> np.random.Generator:
    """The generator for one episode: independent of the others and of run order, so
    `evaluate` and `fit` draw the same tie-breaks for the same episode and seed."""
    return np.random.default_rng([seed, index])


def strategy_factory(name: str, params: Mapping[str, float] | None, dims: str, form: str,
                     axis_weights: Any = None, **options: Any,
                     ) -> Callable[[np.random.Generator], Strategy]:
    make_strategy(name, params=params, dims=dims, form=form, axis_weights=axis_weights,
                  **options)  # fail early on bad names or parameters

    def make(rng: np.random.Generator) -> Strategy:
        return make_strategy(name, params=params, dims=dims, form=form,
                             axis_weights=axis_weights, rng=rng, **options)
    return make


def score_episode(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                  metric: str, repeats: int, rng: np.random.Generator) -> float:
    if metric == "ape":
        return sampled_ape(make, episode, repeats, rng)
    if metric == "expected-ape":
        return expected_ape(make(rng), episode)
    if metric in ("edit", "edit-unrestricted"):
        return sampled_edit(make, episode, repeats, rng, restricted=metric == "edit")
    raise ValueError(f"unknown metric {metric!r}; expected one of {', '.join(METRICS)}")


def baseline_score(episode: Episode, metric: str, rng: np.random.Generator) -> tuple[float, bool]:
    """The random-order baseline of an episode under a metric, and whether it is exact."""
    if metric in ("ape", "expected-ape"):
        return random_ape(episode), True
    return random_edit(episode, rng, restricted=metric == "edit")


def summarise(values: Sequence[float]) -> dict[str, float]:
    return {"episodes": len(values), "mean": float(np.mean(values)) if values else float("nan"),
            "median": float(statistics.median(values)) if values else float("nan")}


@dataclass
class Evaluation:
    strategy: str
    metric: str
    scores: list[float]
    episodes: list[Episode]
    baselines: list[float] = field(default_factory=list)
    baseline_exact: bool = True
    settings: dict[str, Any] = field(default_factory=dict)
    #: Episodes the strategy could not score (id, reason), e.g. too long for `optimal`.
    skipped: list[tuple[str, str]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        by_activity: dict[str, list[float]] = {}
        for ep, score in zip(self.episodes, self.scores, strict=True):
            by_activity.setdefault(ep.activity, []).append(score)
        out = {"strategy": self.strategy, "metric": self.metric, **self.settings,
               **summarise(self.scores),
               "by_activity": {a: summarise(v) for a, v in sorted(by_activity.items())},
               "random_baseline": {**summarise(self.baselines), "exact": self.baseline_exact},
               "skipped": [{"id": i, "reason": r} for i, r in self.skipped],
               "per_episode": [{"id": ep.id, "activity": ep.activity, "length": len(ep),
                                "score": s, "random_baseline": b}
                               for ep, s, b in zip(self.episodes, self.scores, self.baselines,
                                                   strict=True)]}
        return out


def evaluate(episodes: Sequence[Episode], strategy: str = "opm",
             params: Mapping[str, float] | None = None, dims: str = "xy", form: str = "power",
             metric: str = "ape", repeats: int = 100, seed: int = 0, axis_weights: Any = None,
             progress: Callable[[int], None] | None = None) -> Evaluation:
    """Score `strategy` on every episode (the per-episode generators follow `seed`)."""
    make = strategy_factory(strategy, params, dims, form, axis_weights)
    scores, baselines, exact, scored, skipped = [], [], True, [], []
    for index, episode in enumerate(episodes):
        if progress:
            progress(1)
        try:
            score = score_episode(make, episode, metric, repeats, episode_rng(seed, index))
        except StrategyError as exc:
            skipped.append((episode.id, str(exc)))
            continue
        scores.append(score)
        scored.append(episode)
        value, is_exact = baseline_score(episode, metric, episode_rng(seed, index))
        baselines.append(value)
        exact &= is_exact
    settings = {"params": dict(params or {}), "dims": dims, "form": form, "repeats": repeats,
                "seed": seed}
    return Evaluation(strategy, metric, scores, scored, baselines, exact, settings, skipped)
