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
    random_nll,
    random_order_edit,
    sampled_ape,
    sampled_edit,
)
from cramlite.evaluation.options import METRICS
from cramlite.evaluation.protocol import is_reference
from cramlite.strategies.base import Strategy, StrategyCrashed, StrategyError
from cramlite.strategies.registry import make_strategy, strategy_class
from cramlite.strategies.simple import RandomStrategy

#: What the reported numbers are, said in the JSON.
SCORE_KINDS = {
    "sampled": "median over the repeats of the random tie-breaks",
    "exact": "exact expectation over the random tie-breaks",
    "expectation": "expectation over uniformly random orders (exact unless flagged)",
}
BASELINE_KINDS = {
    "ape": "expected APE of guessing uniformly among the offered items (exact)",
    "edit": "published convention (the data's error column): mean restricted distance "
            "between random orders of n distinct items",
}


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


def is_random(name: str) -> bool:
    try:
        return issubclass(strategy_class(name), RandomStrategy)
    except StrategyError:
        return False


def random_expectation(episode: Episode, metric: str, protocol: str = "heldout",
                       ) -> tuple[float, bool]:
    """The `random` strategy's expected score on an episode under a metric: (value, exact)."""
    if metric in ("ape", "expected-ape"):
        return random_ape(episode, protocol), True
    return random_order_edit(episode, metric == "edit", protocol)


def score_episode(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                  metric: str, repeats: int, rng: np.random.Generator,
                  protocol: str = "heldout") -> float:
    if protocol == "thesis" and metric in ("ape", "expected-ape"):
        learned = getattr(make(rng), "learned", None)
        if learned is not None:  # learned models: unrestricted predictions (thesis 3.3.4)
            from cramlite.learning.scoring import thesis_ape

            return thesis_ape(learned, episode, repeats, rng)
    if metric == "ape":
        return sampled_ape(make, episode, repeats, rng, protocol)
    if metric == "expected-ape":
        return expected_ape(make(rng), episode, protocol)
    if metric in ("edit", "edit-unrestricted"):
        return sampled_edit(make, episode, repeats, rng, metric == "edit", protocol)
    raise ValueError(f"unknown metric {metric!r}; expected one of {', '.join(METRICS)}")


def baseline_score(episode: Episode, metric: str, rng: np.random.Generator | None = None,
                   protocol: str = "heldout") -> tuple[float, bool]:
    """The published random baseline of an episode under a metric, and whether it is
    exact: APE of uniform guessing; for edit the data's `error` convention (restricted
    distance over n distinct symbols; unrestricted for `edit-unrestricted` except under
    the reference protocol, whose baseline column is the restricted one); for the
    likelihood, the negative log-likelihood of uniform guessing."""
    if metric in ("ape", "expected-ape"):
        return random_ape(episode, protocol), True
    if metric == "likelihood":
        return random_nll(episode, protocol), True
    return random_edit(episode, restricted=metric == "edit" or is_reference(protocol))


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
    #: "sampled", "exact" or "expectation" (see SCORE_KINDS), and per-episode exactness.
    score_kind: str = "sampled"
    exact: list[bool] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        by_activity: dict[str, list[float]] = {}
        for ep, score in zip(self.episodes, self.scores, strict=True):
            by_activity.setdefault(ep.activity, []).append(score)
        exact = self.exact or [True] * len(self.scores)
        kind = "ape" if self.metric in ("ape", "expected-ape") else "edit"
        return {"strategy": self.strategy, "metric": self.metric, **self.settings,
                "score_kind": self.score_kind, "score_definition": SCORE_KINDS[self.score_kind],
                **summarise(self.scores),
                "by_activity": {a: summarise(v) for a, v in sorted(by_activity.items())},
                "random_baseline": {**summarise(self.baselines), "exact": self.baseline_exact,
                                    "definition": BASELINE_KINDS[kind]},
                "skipped": [{"id": i, "reason": r} for i, r in self.skipped],
                "per_episode": [{"id": ep.id, "activity": ep.activity, "length": len(ep),
                                 "score": s, "score_exact": x, "random_baseline": b}
                                for ep, s, x, b in zip(self.episodes, self.scores, exact,
                                                       self.baselines, strict=True)]}


def evaluate(episodes: Sequence[Episode], strategy: str = "opm",
             params: Mapping[str, float] | None = None, dims: str = "xy", form: str = "power",
             metric: str = "ape", repeats: int = 100, seed: int = 0, axis_weights: Any = None,
             progress: Callable[[int], None] | None = None,
             protocol: str = "heldout", data_sha256: str | None = None) -> Evaluation:
    """Score `strategy` on every episode (the per-episode generators follow `seed`).

    The `random` strategy is scored by its expectation (a function of the episode only),
    not by sampling: a median of random orders would read like a better baseline. A
    learned model under `heldout` is scored on its test episodes when `data_sha256` is
    its training file's hash."""
    is_reference(protocol)  # validates the name
    make = strategy_factory(strategy, params, dims, form, axis_weights)
    scope = "all episodes"
    if strategy.startswith("learned:"):
        from cramlite.learning.scoring import episodes_to_score

        given = len(episodes)
        episodes = episodes_to_score(strategy, episodes, protocol, data_sha256)
        if len(episodes) < given:
            scope = "the model's test split"
    expectation = is_random(strategy)
    scores, baselines, exact_base, scored, skipped, exact = [], [], True, [], [], []
    for index, episode in enumerate(episodes):
        if progress:
            progress(1)
        try:
            if expectation:
                score, is_exact = random_expectation(episode, metric, protocol)
            else:
                score = score_episode(make, episode, metric, repeats,
                                      episode_rng(seed, index), protocol)
                is_exact = True
        except StrategyCrashed:
            raise  # a bug in the strategy: stop, the rest would fail the same way
        except StrategyError as exc:  # it cannot handle this episode (e.g. too many items)
            skipped.append((episode.id, str(exc)))
            continue
        scores.append(score)
        exact.append(is_exact)
        scored.append(episode)
        value, base_exact = baseline_score(episode, metric, protocol=protocol)
        baselines.append(value)
        exact_base &= base_exact
    settings = {"params": dict(params or {}), "dims": dims, "form": form, "repeats": repeats,
                "seed": seed, "protocol": protocol}
    settings["scored"] = scope
    kind = "expectation" if expectation else ("exact" if metric == "expected-ape" else
                                              "sampled")
    return Evaluation(strategy, metric, scores, scored, baselines, exact_base, settings,
                      skipped, kind, exact)
