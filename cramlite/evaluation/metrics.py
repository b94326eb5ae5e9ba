"""Scoring a strategy against one recorded episode (thesis 3.3), under a protocol
(`cramlite.evaluation.protocol` says what is offered at each step).

- Edit distance: normalised Damerau-Levenshtein between a generated and the observed
  sequence (Eq. 3.4), restricted (optimal string alignment, the thesis's baselines) or
  unrestricted, from rapidfuzz (normalised by the longer sequence).
- APE (prequential, teacher-forced): at each step i < n-1 predict the next item from
  the observed position before step i among the items offered; error 1 if it is not
  the observed item; the observed item is what is taken. Sampled: the median over n
  repeats of the random tie-breaks. Expected: the exact mean over tie-breaks, 1 - t/|T|
  at a step whose lowest cost is shared by the set T of which t carry the observed name.
- Strategies with a history (`observe`, e.g. opm-2step) are told the observed item
  after each scored step, so they reason from what the subject did.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections import Counter
from collections.abc import Callable, Iterator, Sequence

import numpy as np
from rapidfuzz import process
from rapidfuzz.distance import OSA, DamerauLevenshtein

from cramlite.evaluation.data import Episode
from cramlite.evaluation.protocol import ape_steps, generation_candidates, is_reference, pool
from cramlite.strategies.base import Strategy, checked_choice, checked_reset, checked_tied

#: Above this many items the published random edit baseline is sampled, not enumerated.
EXACT_PERMUTATION_LIMIT = 9
#: Above this many distinct orders the random strategy's expected edit is sampled.
EXACT_ORDERS_LIMIT = 50_000
BASELINE_SAMPLES = 20_000


def edit_distance(a: Sequence[str], b: Sequence[str], restricted: bool = True) -> float:
    """Normalised Damerau-Levenshtein distance (0 identical .. 1 maximally different)."""
    metric = OSA if restricted else DamerauLevenshtein
    return float(metric.normalized_distance(list(a), list(b)))


def exact_ties(strategy: Strategy) -> bool:
    """True when `tied` is the exact set the strategy picks uniformly from at each step."""
    return bool(strategy.memoryless or getattr(strategy, "exact_ties", False))


def _observe(strategy: Strategy, taken) -> None:
    observe = getattr(strategy, "observe", None)
    if observe is not None:
        observe(taken)


def correct_probabilities(strategy: Strategy, episode: Episode,
                          protocol: str = "heldout") -> list[float]:
    """P(prediction == observed) at each scored step, for a strategy with exact ties."""
    checked_reset(strategy, pool(episode, protocol), episode.start_positions[0])
    probs = []
    for step in ape_steps(episode, protocol):
        tied = checked_tied(strategy, step.candidates, step.agent)
        probs.append(sum(c.name == step.observed_name for c in tied) / len(tied))
        _observe(strategy, step.candidates[step.observed])
    return probs


def expected_ape(strategy: Strategy, episode: Episode, protocol: str = "heldout") -> float:
    """Exact expectation of the APE over uniform tie-breaks."""
    if not exact_ties(strategy):
        from cramlite.strategies.base import strategy_label

        raise ValueError(f"expected-ape needs a strategy whose ties are known; "
                         f"{strategy_label(strategy)} remembers its own random choices: use "
                         "the sampled 'ape' metric")
    return float(sum(1.0 - p for p in correct_probabilities(strategy, episode, protocol)))


def sampled_errors(probs: np.ndarray, uniforms: np.ndarray) -> np.ndarray:
    """APE per repeat from per-step P(correct) (steps, ...) and uniforms (repeats, steps)."""
    return (uniforms.reshape(uniforms.shape + (1,) * (probs.ndim - 1)) >= probs).sum(axis=1)


def ape_uniforms(rng: np.random.Generator, repeats: int, steps: int) -> np.ndarray:
    return rng.random((repeats, steps))


def prequential_errors(strategy: Strategy, episode: Episode,
                       protocol: str = "heldout") -> tuple[int, int]:
    """One teacher-forced run of any strategy: (errors, random picks that had a choice)."""
    checked_reset(strategy, pool(episode, protocol), episode.start_positions[0])
    errors = 0
    picks_before = _random_picks(strategy)
    for step in ape_steps(episode, protocol):
        chosen = checked_choice(strategy, list(step.candidates), step.agent)
        errors += chosen.name != step.observed_name
        _observe(strategy, step.candidates[step.observed])
    return errors, _random_picks(strategy) - picks_before


def _random_picks(strategy: Strategy) -> int:
    return getattr(strategy, "random_picks", 0)


def sampled_ape(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                repeats: int, rng: np.random.Generator, protocol: str = "heldout") -> float:
    """Median APE over `repeats` runs with random tie-breaks (the source's score)."""
    if len(episode) < 2:
        return 0.0
    probe = make(rng)
    if exact_ties(probe):
        probs = np.asarray(correct_probabilities(probe, episode, protocol))
        uniforms = ape_uniforms(rng, repeats, len(probs))
        return float(np.median(sampled_errors(probs, uniforms)))
    results = []
    for r in range(repeats):
        strategy = probe if r == 0 else make(rng)
        errors, random_picks = prequential_errors(strategy, episode, protocol)
        results.append(errors)
        if r == 0 and random_picks == 0:  # nothing random happened: all repeats agree
            return float(errors)
    return float(np.median(results))


def generate_sequence(strategy: Strategy, episode: Episode,
                      protocol: str = "heldout") -> list[str]:
    """Algorithm 1: the strategy's own sequence, from the observed position before each step
    (over the distinct names under the reference protocol)."""
    items = pool(episode, protocol)
    remaining = list(range(len(items)))
    checked_reset(strategy, items, episode.start_positions[0])
    order = []
    for step in range(len(items)):
        candidates = generation_candidates(episode, protocol, step, remaining)
        chosen = checked_choice(strategy, candidates, episode.start_positions[step])
        index = remaining[candidates.index(chosen)]
        order.append(items[index].name)
        remaining.remove(index)
    return order


def model_edit(generated: Sequence[str], observed: Sequence[str], restricted: bool,
               protocol: str = "heldout") -> float:
    """The edit score of a generated sequence (always unrestricted under `reference`)."""
    return edit_distance(generated, observed, restricted and not is_reference(protocol))


def sampled_edit(make: Callable[[np.random.Generator], Strategy], episode: Episode,
                 repeats: int, rng: np.random.Generator, restricted: bool = True,
                 protocol: str = "heldout") -> float:
    """Median normalised edit distance of generated vs observed over `repeats` runs."""
    results = []
    for r in range(repeats):
        strategy = make(rng)
        picks_before = _random_picks(strategy)
        generated = generate_sequence(strategy, episode, protocol)
        results.append(model_edit(generated, episode.sequence, restricted, protocol))
        if r == 0 and _random_picks(strategy) == picks_before:
            return results[0]
    return float(np.median(results))


def random_ape(episode: Episode, protocol: str = "heldout") -> float:
    """Exact expected APE of uniformly random guessing among the offered items."""
    return float(sum(1.0 - sum(c.name == step.observed_name for c in step.candidates)
                     / len(step.candidates) for step in ape_steps(episode, protocol)))


def random_nll(episode: Episode, protocol: str = "heldout") -> float:
    """Negative log-likelihood of the observed choices under uniformly random guessing
    among the offered items (nats)."""
    return float(sum(math.log(len(step.candidates))
                     - math.log(sum(c.name == step.observed_name for c in step.candidates))
                     for step in ape_steps(episode, protocol)))


def random_order_edit(episode: Episode, restricted: bool = True, protocol: str = "heldout",
                      ) -> tuple[float, bool]:
    """Expected edit score of the `random` strategy: a uniformly random order of the
    offered items against the observed sequence (a function of the episode only).
    Exact by enumerating the distinct name orders when there are at most
    EXACT_ORDERS_LIMIT of them, else the mean of BASELINE_SAMPLES orders drawn with a
    seed fixed by the episode. Returns (value, exact)."""
    names = [c.name for c in pool(episode, protocol)]
    symbols = {n: chr(0x100 + i) for i, n in enumerate(sorted(set(names)))}
    observed = "".join(symbols[n] for n in episode.sequence)
    letters = [symbols[n] for n in names]
    scorer = (OSA if restricted and not is_reference(protocol) else DamerauLevenshtein)
    count = math.factorial(len(letters))
    for times in Counter(letters).values():
        count //= math.factorial(times)
    exact = count <= EXACT_ORDERS_LIMIT
    if exact:
        orders = ["".join(p) for p in _distinct_permutations(sorted(letters))]
    else:
        seed = [len(letters), *map(ord, observed), int(restricted)]
        rng = np.random.default_rng(seed)
        orders = ["".join(rng.permutation(letters)) for _ in range(BASELINE_SAMPLES)]
    scores = process.cdist([observed], orders, scorer=scorer.normalized_distance)
    return float(np.mean(scores)), exact


def _distinct_permutations(items: list[str]) -> Iterator[tuple[str, ...]]:
    """Every distinct order of a multiset, once each (items sorted)."""
    counts = Counter(items)
    keys = sorted(counts)
    current: list[str] = []

    def walk() -> Iterator[tuple[str, ...]]:
        if len(current) == len(items):
            yield tuple(current)
            return
        for key in keys:
            if counts[key]:
                counts[key] -= 1
                current.append(key)
                yield from walk()
                current.pop()
                counts[key] += 1
    return walk()


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
