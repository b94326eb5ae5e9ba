"""Scoring a strategy against one recorded episode (thesis 3.3).

- Edit distance: normalised Damerau-Levenshtein between a generated and the observed
  sequence (Eq. 3.4), restricted (optimal string alignment, the thesis's baselines) or
  unrestricted, from rapidfuzz.
- APE (prequential, teacher-forced): at each step i < n-1 predict the next item from
  the observed position before step i among the items not yet taken; error 1 if it is
  not the observed item; the observed item is removed. Sampled: the median over n
  repeats of the random tie-breaks. Expected: the exact mean over tie-breaks, 1 - t/|T|
  at a step whose lowest cost is shared by the set T of which t carry the observed name.

The candidates are the items of the episode's action list (Algorithm 1); a repeated
name is one candidate per occurrence, at its own position. They are offered sorted by
(name, position), never in the observed order, which would tell the answer (to
`baseline`, for one). Where a strategy looks ahead, the agent stands after step i
where the subject stood before step i+1.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from rapidfuzz.distance import OSA, DamerauLevenshtein

from cramlite.evaluation.data import Episode
from cramlite.strategies.base import Strategy
from cramlite.strategies.candidates import Candidate

#: Above this many items the random edit baseline is sampled, not enumerated.
EXACT_PERMUTATION_LIMIT = 9
BASELINE_SAMPLES = 20_000


def edit_distance(a: Sequence[str], b: Sequence[str], restricted: bool = True) -> float:
    """Normalised Damerau-Levenshtein distance (0 identical .. 1 maximally different)."""
    metric = OSA if restricted else DamerauLevenshtein
    return float(metric.normalized_distance(list(a), list(b)))


def neutral_order(episode: Episode) -> list[int]:
    """Indices of the episode's steps, ordered by (name, position): no hint of the answer."""
    items = episode.sequence_items()
    return sorted(range(len(items)), key=lambda j: (items[j].name, items[j].position, j))


@functools.lru_cache(maxsize=512)
def _lookahead_items(episode: Episode) -> tuple[tuple[Candidate, ...], ...]:
    """Per step, every item with `then_at` = where the subject stood before the next step
    (built once per episode: repeats and grid points reuse it)."""
    items = episode.sequence_items()
    out = []
    for step in range(len(episode)):
        then_at = episode.start_positions[step + 1] if step + 1 < len(episode) else None
        out.append(tuple(replace(item, then_at=then_at) for item in items))
    return tuple(out)


def _step_candidates(episode: Episode, remaining: Sequence[int], step: int) -> list[Candidate]:
    at_step = _lookahead_items(episode)[step]
    return [at_step[j] for j in remaining]


def correct_probabilities(strategy: Strategy, episode: Episode) -> list[float]:
    """P(prediction == observed) at each scored step, for a memoryless strategy."""
    items = episode.sequence_items()
    remaining = neutral_order(episode)
    strategy.reset(items, episode.start_positions[0])
    probs = []
    for step in range(len(episode) - 1):
        tied = strategy.tied([items[j] for j in remaining], episode.start_positions[step])
        observed = episode.sequence[step]
        probs.append(sum(c.name == observed for c in tied) / len(tied))
        remaining.remove(step)
    return probs


def expected_ape(strategy: Strategy, episode: Episode) -> float:
    """Exact expectation of the APE over uniform tie-breaks (memoryless strategies)."""
    if not strategy.memoryless:
        raise ValueError(f"expected-ape needs a memoryless strategy; {strategy.name!r} "
                         "remembers earlier choices: use the sampled 'ape' metric")
    return float(sum(1.0 - p for p in correct_probabilities(strategy, episode)))


def sampled_errors(probs: np.ndarray, uniforms: np.ndarray) -> np.ndarray:
    """APE per repeat from per-step P(correct) (steps, ...) and uniforms (repeats, steps)."""
    return (uniforms.reshape(uniforms.shape + (1,) * (probs.ndim - 1)) >= probs).sum(axis=1)


def ape_uniforms(rng: np.random.Generator, repeats: int, steps: int) -> np.ndarray:
    return rng.random((repeats, steps))


def prequential_errors(strategy: Strategy, episode: Episode) -> tuple[int, int]:
    """One teacher-forced run of any strategy: (errors, random picks that had a choice)."""
    remaining = neutral_order(episode)
    strategy.reset(episode.sequence_items(), episode.start_positions[0])
    errors = 0
    picks_before = _random_picks(strategy)
    for step in range(len(episode) - 1):
        chosen = strategy.choose(_step_candidates(episode, remaining, step),
                                 episode.start_positions[step])
        errors += chosen.name != episode.sequence[step]
        remaining.remove(step)
    return errors, _random_picks(strategy) - picks_before


def _random_picks(strategy: Strategy) -> int:
    return getattr(strategy, "random_picks", 0)


def sampled_ape(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                repeats: int, rng: np.random.Generator) -> float:
    """Median APE over `repeats` runs with random tie-breaks (the source's score)."""
    if len(episode) < 2:
        return 0.0
    probe = make(rng)
    if probe.memoryless:
        probs = np.asarray(correct_probabilities(probe, episode))
        uniforms = ape_uniforms(rng, repeats, len(probs))
        return float(np.median(sampled_errors(probs, uniforms)))
    results = []
    for r in range(repeats):
        strategy = probe if r == 0 else make(rng)
        errors, random_picks = prequential_errors(strategy, episode)
        results.append(errors)
        if r == 0 and random_picks == 0:  # nothing random happened: all repeats agree
            return float(errors)
    return float(np.median(results))


def generate_sequence(strategy: Strategy, episode: Episode) -> list[str]:
    """Algorithm 1: the strategy's own sequence, from the observed position before each step."""
    remaining = neutral_order(episode)
    strategy.reset(episode.sequence_items(), episode.start_positions[0])
    order = []
    for step in range(len(episode)):
        candidates = _step_candidates(episode, remaining, step)
        chosen = strategy.choose(candidates, episode.start_positions[step])
        index = remaining[candidates.index(chosen)]
        order.append(episode.sequence[index])
        remaining.remove(index)
    return order


def sampled_edit(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                 repeats: int, rng: np.random.Generator, restricted: bool = True) -> float:
    """Median normalised edit distance of generated vs observed over `repeats` runs."""
    results = []
    for r in range(repeats):
        strategy = make(rng)
        picks_before = _random_picks(strategy)
        generated = generate_sequence(strategy, episode)
        results.append(edit_distance(generated, episode.sequence, restricted))
        if r == 0 and _random_picks(strategy) == picks_before:
            return results[0]
    return float(np.median(results))


def random_ape(episode: Episode) -> float:
    """Exact expected APE of uniformly random guessing among the remaining items."""
    total, remaining = 0.0, list(episode.sequence)
    for step in range(len(episode) - 1):
        observed = episode.sequence[step]
        total += 1.0 - remaining.count(observed) / len(remaining)
        remaining.remove(observed)
    return total


def random_edit(episode: Episode, rng: np.random.Generator | None = None,
                restricted: bool = True) -> tuple[float, bool]:
    """Expected edit distance of a random order, as the published baseline defines it:
    the mean normalised distance between random permutations of n distinct symbols (so
    it depends only on the length: 0.666 for 5 items). Returns (value, exact)."""
    return random_permutation_edit(len(episode), restricted)


@functools.cache
def random_permutation_edit(n: int, restricted: bool = True) -> tuple[float, bool]:
    """Mean normalised edit distance over all pairs of permutations of n distinct items.

    Edit distances do not change when symbols are renamed, so the mean over all pairs
    equals the mean distance of every permutation to the identity: exact by enumeration
    up to EXACT_PERMUTATION_LIMIT items, estimated from a fixed-seed sample beyond."""
    if n <= 1:
        return 0.0, True
    identity = list(range(n))
    if n <= EXACT_PERMUTATION_LIMIT:
        total = sum(edit_distance(p, identity, restricted)
                    for p in itertools.permutations(identity))
        return total / math.factorial(n), True
    rng = np.random.default_rng([n, int(restricted)])
    draws = [edit_distance(list(rng.permutation(n)), identity, restricted)
             for _ in range(BASELINE_SAMPLES)]
    return float(np.mean(draws)), False
