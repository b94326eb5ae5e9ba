"""Turning episodes into what the models see: a vocabulary, a seeded episode-level split,
token sequences (RNN, CPT) and per-step context features (NN, thesis Table 3.6).

NN features, per vocabulary item: present in the task, x, y, z (of the next instance
still to fetch, else the last one), k and c (the OPM's best-fit values for its category
and storage), taken before; then the person's x, y, z before the step.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.evaluation.data import Episode
from cramlite.strategies.candidates import Candidate, OPMParams

PER_ITEM = ("present", "x", "y", "z", "k", "c", "taken")
SPLIT_NAMES = ("train", "validation", "test")
#: RNN token ids: 0 pads, 1 starts an episode, items are 2.. (outputs are items 0..V-1).
PAD, START, FIRST_ITEM = 0, 1, 2


def source_of(episode_id: str) -> str:
    """The data source an ID shows (its letter prefix: a, h, E, v, T in the shipped set)."""
    match = re.match(r"[A-Za-z]+", episode_id)
    return match.group(0) if match else "?"


def split_episodes(episodes: Sequence[Episode], fractions: Sequence[float], seed: int,
                   ) -> dict[str, list[str]]:
    """Episode IDs per split (train, validation, test), shuffled with `seed` within each
    data source so every source is spread over the splits in the same proportions.
    (A stratified shuffle split by hand: ten lines instead of a scikit-learn dependency.)"""
    rng = np.random.default_rng(seed)
    out: dict[str, list[str]] = {name: [] for name in SPLIT_NAMES}
    by_source: dict[str, list[str]] = {}
    for ep in episodes:
        by_source.setdefault(source_of(ep.id), []).append(ep.id)
    for source in sorted(by_source):
        ids = [by_source[source][i] for i in rng.permutation(len(by_source[source]))]
        n_train = round(fractions[0] * len(ids))
        n_val = round(fractions[1] * len(ids))
        out["train"] += ids[:n_train]
        out["validation"] += ids[n_train:n_train + n_val]
        out["test"] += ids[n_train + n_val:]
    return out


@dataclass(frozen=True)
class Vocabulary:
    """The item names a model knows, in a fixed order."""

    names: tuple[str, ...]

    @classmethod
    def of(cls, episodes: Sequence[Episode]) -> Vocabulary:
        return cls(tuple(sorted({n for ep in episodes for n in ep.sequence})))

    def __len__(self) -> int:
        return len(self.names)

    def index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.names)}


def token_of(candidate: Candidate, known: Mapping[str, int]) -> str | None:
    """The vocabulary name a candidate stands for: its name, an alias, or its type
    (from `metadata`, filled by the robot's plans); None if the model never saw it."""
    if candidate.name in known:
        return candidate.name
    meta = candidate.metadata or {}
    for alias in meta.get("aliases") or ():
        if alias in known:
            return alias
    kind = meta.get("type")
    return kind if kind in known else None


def rnn_arrays(episodes: Sequence[Episode], vocab: Vocabulary,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inputs (start + all but the last item), targets (the items) and a mask, padded."""
    index = vocab.index()
    length = max(len(ep) for ep in episodes)
    x = np.zeros((len(episodes), length), dtype=np.int32)
    y = np.zeros((len(episodes), length), dtype=np.int32)
    mask = np.zeros((len(episodes), length), dtype=np.float32)
    for row, ep in enumerate(episodes):
        ids = [index[n] for n in ep.sequence]
        x[row, :len(ids)] = [START] + [FIRST_ITEM + i for i in ids[:-1]]
        y[row, :len(ids)] = ids
        mask[row, :len(ids)] = 1.0
    return x, y, mask


def nn_features(vocab_index: Mapping[str, int], remaining: Sequence[Candidate],
                taken: Sequence[str], agent: Sequence[float],
                params: OPMParams | None = None) -> np.ndarray:
    """One step's context vector (thesis Table 3.6); `remaining` and `taken` hold
    vocabulary names (unknown items are left out by the caller)."""
    params = params or OPMParams()
    size = len(vocab_index)
    table = np.zeros((size, len(PER_ITEM)), dtype=np.float32)
    for name in taken:
        row = vocab_index[name]
        table[row, 0] = 1.0
        table[row, 6] = 1.0
    for item in reversed(remaining):  # the first listed instance of a name wins
        row = vocab_index[item.name]
        table[row, 0] = 1.0
        table[row, 1:4] = item.position
        table[row, 4] = params.k_of(item)
        table[row, 5] = params.c_of(item)
    return np.concatenate([table.ravel(), np.asarray(agent, dtype=np.float32)[:3]])


def nn_arrays(episodes: Sequence[Episode], vocab: Vocabulary,
              ) -> tuple[np.ndarray, np.ndarray]:
    """Every step of every episode as (features, index of the item taken)."""
    from cramlite.evaluation.protocol import pool

    index = vocab.index()
    rows, targets = [], []
    for ep in episodes:
        for step, (remaining, taken) in enumerate(episode_states(ep, pool(ep))):
            rows.append(nn_features(index, remaining, taken, ep.start_positions[step]))
            targets.append(index[ep.sequence[step]])
    return np.asarray(rows, dtype=np.float32), np.asarray(targets, dtype=np.int32)


def episode_states(episode: Episode, items: Sequence[Candidate],
                   ) -> list[tuple[list[Candidate], list[str]]]:
    """Before each step: the items still to fetch and the names taken so far."""
    remaining, taken, out = list(items), [], []
    for name in episode.sequence:
        out.append((list(remaining), list(taken)))
        same = next(i for i, c in enumerate(remaining) if c.name == name)
        remaining.pop(same)
        taken.append(name)
    return out
