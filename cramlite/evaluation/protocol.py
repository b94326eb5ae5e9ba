"""What a strategy is offered at each step of a recorded episode, under a protocol.

`cramlite` (used by the `heldout` and `thesis` protocols too): the candidates are the
items of the action list (Algorithm 1), one per occurrence of a name, at its own listed
position; the observed item is removed after each step; a containment or k list names
an item exactly. Edit distances compare sequences of equal length.

`reference`: the conventions of the published OPM implementation, point by point:
  1. candidates are the distinct names, each at the last coordinate listed for it;
  2. in APE, the candidates at step i are the distinct names still to come in the
     observed sequence (seq[i:]): a repeated name stays until its last occurrence;
  3. a sequence is generated over the distinct names (so it can be shorter than the
     observed one), one start position per generated step;
  4. the model's edit distance is the unrestricted Damerau-Levenshtein normalised by
     the longer sequence (its random baseline, the data's `error` column, uses the
     restricted one over n distinct symbols: `random_edit`);
  5. an item is in closed storage when its name is a substring of the containment
     cell (so `plate` is contained where `plate2` is); k categories match exactly.

Candidates are offered sorted by (name, position), never in the observed order, which
would tell the answer. Where a strategy looks ahead, every item's `then_at` at step i is
where the subject stood before step i+1.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, replace

from cramlite.evaluation.data import Episode
from cramlite.evaluation.options import PROTOCOLS
from cramlite.strategies.candidates import Candidate, Position


@dataclass(frozen=True)
class Step:
    """One scored (teacher-forced) step: what is offered, from where, and what was taken."""

    candidates: tuple[Candidate, ...]
    agent: Position
    observed: int  # index into candidates of the item the subject took

    @property
    def observed_name(self) -> str:
        return self.candidates[self.observed].name


def is_reference(protocol: str) -> bool:
    if protocol not in PROTOCOLS:
        raise ValueError(f"unknown protocol {protocol!r}; expected one of "
                         f"{', '.join(PROTOCOLS)}")
    return protocol == "reference"


@functools.lru_cache(maxsize=1024)
def pool(episode: Episode, protocol: str = "heldout") -> tuple[Candidate, ...]:
    """The episode's candidates in neutral order (sorted by name, then position)."""
    if is_reference(protocol):
        wanted, last = set(episode.sequence), {}
        for item in episode.items:
            if item.name in wanted:
                last[item.name] = item
        containment = episode.cells.get("containment", "")
        items = [replace(c, contained=c.name in containment) for c in last.values()]
    else:
        items = list(episode.sequence_items())
    order = sorted(range(len(items)), key=lambda j: (items[j].name, items[j].position, j))
    return tuple(items[j] for j in order)


def _then_at(episode: Episode, step: int) -> Position | None:
    return episode.start_positions[step + 1] if step + 1 < len(episode) else None


@functools.lru_cache(maxsize=1024)
def ape_steps(episode: Episode, protocol: str = "heldout") -> tuple[Step, ...]:
    """The scored steps i < n-1 of the teacher-forced APE."""
    items = pool(episode, protocol)
    steps = []
    if is_reference(protocol):
        index = {c.name: j for j, c in enumerate(items)}
        for i in range(len(episode) - 1):
            ahead = set(episode.sequence[i:])
            chosen = [j for j, c in enumerate(items) if c.name in ahead]
            steps.append(_step(episode, i, items, chosen, index[episode.sequence[i]]))
        return tuple(steps)
    # one candidate per occurrence: the observed occurrence is the pool entry that is
    # this step's sequence item (pool() is a permutation of the sequence items)
    order = _occurrence_order(episode)
    remaining = list(range(len(items)))
    for i in range(len(episode) - 1):
        steps.append(_step(episode, i, items, remaining, order[i]))
        remaining.remove(order[i])
    return tuple(steps)


def _occurrence_order(episode: Episode) -> list[int]:
    """For each step, the index in pool() of the item taken at that step."""
    items = list(episode.sequence_items())
    order = sorted(range(len(items)), key=lambda j: (items[j].name, items[j].position, j))
    where = {step: rank for rank, step in enumerate(order)}
    return [where[step] for step in range(len(items))]


def _step(episode: Episode, i: int, items: Sequence[Candidate], chosen: Sequence[int],
          observed: int) -> Step:
    then_at = _then_at(episode, i)
    offered = tuple(replace(items[j], then_at=then_at) for j in chosen)
    return Step(offered, episode.start_positions[i], list(chosen).index(observed))


def generation_candidates(episode: Episode, protocol: str, step: int,
                          remaining: Sequence[int]) -> list[Candidate]:
    """The pool entries `remaining` as offered when generating step `step`."""
    items = pool(episode, protocol)
    then_at = _then_at(episode, step)
    return [replace(items[j], then_at=then_at) for j in remaining]
