"""Strategies without a cost model: the given order, and a seeded random order."""

from __future__ import annotations

from collections.abc import Sequence

from cramlite.strategies.base import Strategy
from cramlite.strategies.candidates import Candidate


class BaselineStrategy(Strategy):
    """The fixed order of the task (the source's baseline, Table 4.2).

    The order is `order=[names]` if given, else the order in which candidates are listed.
    """

    name = "baseline"
    uses_params = False
    summary = "the fixed order given by the task (setup file's baseline_order)"

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        order = self.options.get("order")
        if not order:
            return remaining[0]
        rank = {name: i for i, name in reversed(list(enumerate(order)))}
        return min(remaining, key=lambda c: rank.get(c.name, len(rank)))


class RandomStrategy(Strategy):
    name = "random"
    uses_params = False
    summary = "a seeded random permutation (uniform over the remaining items)"

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        return list(remaining)

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        return self._pick(list(remaining))
