"""Scoring learned models under the two protocols of issue 12.

`heldout` (default): on the model's own training file only its test episodes are scored
(any other file: every episode, i.e. generalisation); predictions are restricted to the
items not yet taken (the strategy path, as for the OPM).

`thesis`: the protocol behind the published figures (thesis 3.3.4): every episode is
scored, training episodes included, and predictions are not restricted to the remaining
items (a model may predict an item already taken, or one not in the task):
  - RNN: from a fresh state primed with the previous item only (a start token before the
    first), the output divided by the temperature 0.4 and sampled; the episode's score
    is the median APE over the repeats;
  - NN: the most likely item given the step's context;
  - CPT: its top prediction from the observed prefix, every position scored (n, not
    n - 1; the first from the empty prefix).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.evaluation.protocol import pool
from cramlite.learning.encoding import episode_states, nn_features
from cramlite.learning.modelfile import LearnedModel, load_model
from cramlite.learning.models import CPTModel, NNModel, RNNModel
from cramlite.learning.strategy import PREFIX, THESIS_TEMPERATURE


def file_sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def episodes_to_score(strategy: str, episodes: Sequence[Episode], protocol: str,
                      data_sha256: str | None) -> list[Episode]:
    """Under `heldout`, a learned model's own training file is scored on its test split."""
    if not strategy.startswith(PREFIX) or protocol != "heldout" or data_sha256 is None:
        return list(episodes)
    model = load_model(strategy[len(PREFIX):])
    if model.meta.get("data", {}).get("sha256") != data_sha256:
        return list(episodes)
    test = set(model.test_ids())
    scored = [ep for ep in episodes if ep.id in test]
    if not scored:
        from cramlite.strategies.base import StrategyError

        raise StrategyError(
            f"{strategy} was trained on this file, and its test split holds none of its "
            f"{len(episodes)} episodes: under --protocol heldout nothing is left to score "
            "it on; train it with a larger test fraction (--split) or on more episodes, "
            "or score it on another file")
    return scored


#: What `thesis_ape` may vary, for the ablation of `cramlite reproduce` (the defaults are
#: the protocol): which positions are scored (`n-1`, the APE's; `n`, every one, as for
#: the CPT), what primes the RNN after an item it never saw (`last-known`: the last item
#: it knows; `start`: the start token), and how the RNN picks (`sample` at the
#: temperature, or `argmax`).
ABLATIONS = {"positions": ("n-1", "n"), "unseen_prime": ("last-known", "start"),
             "choice": ("sample", "argmax")}


def thesis_ape(model: LearnedModel, episode: Episode, repeats: int,
               rng: np.random.Generator, positions: str = "n-1",
               unseen_prime: str = "last-known", choice: str = "sample") -> float:
    """The APE of one episode under the thesis protocol (see the module docstring). An
    item the model never saw cannot be its output, so a step that takes one is an error."""
    index, names = model.index, model.vocab.names
    known = [n if n in index else None for n in episode.sequence]
    if isinstance(model.net, CPTModel):
        errors = 0
        for i, observed in enumerate(episode.sequence):
            scores = model.net.scores([n for n in known[:i] if n is not None])
            errors += not (np.isfinite(scores).any() and names[int(np.argmax(scores))]
                           == observed)
        return float(errors)
    steps = len(episode) - (1 if positions == "n-1" else 0)
    if isinstance(model.net, NNModel):
        states = episode_states(episode, pool(episode))
        errors = 0
        for i in range(steps):
            remaining, taken = states[i]
            remaining = [c for c in remaining if c.name in index]
            taken = [n for n in taken if n in index]
            logits = model.net.logits(nn_features(index, remaining, taken,
                                                  episode.start_positions[i]))
            errors += names[int(np.argmax(logits))] != episode.sequence[i]
        return float(errors)
    assert isinstance(model.net, RNNModel)
    probabilities = []
    for i in range(steps):
        history = [index[n] for n in known[:i] if n is not None]
        if unseen_prime == "start" and i > 0 and known[i - 1] is None:
            history = []  # (primed with the start token)
        logits = model.net.logits(history, prime_only=True) / THESIS_TEMPERATURE
        if choice == "argmax":
            p = (logits == logits.max()).astype(float)
        else:
            p = np.exp(logits - logits.max())
        probabilities.append(p / p.sum())
    draws = np.array([[rng.choice(len(names), p=p) for p in probabilities]
                      for _ in range(repeats)]).reshape(repeats, steps)
    observed = np.array([index.get(n, -1) for n in episode.sequence[:steps]])
    return float(np.median((draws != observed).sum(axis=1)))


def unseen_steps(model: LearnedModel, episode: Episode, positions: str = "n-1") -> int:
    """Scored steps that take an item the model never saw: errors whatever it predicts
    (the lowest APE a model restricted to its training vocabulary can reach)."""
    steps = len(episode) - (1 if positions == "n-1" else 0)
    return sum(n not in model.index for n in episode.sequence[:steps])
