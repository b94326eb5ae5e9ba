"""Strategies that choose what to carry together (one item per free hand; thesis 6.2).

`opm-batch`: the OPM's stepwise choice made once per free hand before delivering. The
first item i = argmin over the remaining items of d(robot, i)^k_i * c_i; the next one
j = argmin over the rest of d(fetch_at(i), j)^k_j * c_j, seen from where i is taken (its
`fetch_at`); and so on up to the capacity. It commits to the whole batch, unlike
`opm-2step`, which looks two steps ahead but commits to one item.
`nearest-batch`: the same with k = c = 1. `random-batch`: a seeded uniform sample.
`optimal-batch`: the batch that begins a least-cost plan of trips for every remaining
item (exact, over every way of grouping and ordering them, for small sets): a trip of
items i then j from where the agent stands at p costs C(p, i) + C(fetch_at(i), j), and
the items are delivered in the order they were fetched, so it ends at j's `then_at`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from functools import cache

from cramlite.strategies.base import StrategyError
from cramlite.strategies.candidates import Candidate, Position
from cramlite.strategies.opm import NearestStrategy, OPMStrategy
from cramlite.strategies.optimal import OptimalStrategy
from cramlite.strategies.simple import RandomStrategy

#: optimal-batch plans exactly for at most this many items (2^n subsets x n^3 steps).
MAX_OPTIMAL_BATCH_ITEMS = 10


class OPMBatchStrategy(OPMStrategy):
    name = "opm-batch"
    summary = ("OPM per free hand: the next item seen from where the previous one of the "
               "batch is taken, then deliver them all")

    def choose_batch(self, remaining: Sequence[Candidate], agent: Sequence[float],
                     capacity: int) -> list[Candidate]:
        rest, batch, here = list(remaining), [], tuple(agent)
        while rest and len(batch) < capacity:
            chosen = self.greedy(rest, here)
            batch.append(chosen)
            rest.remove(chosen)
            here = chosen.fetch_position()
        return batch


class NearestBatchStrategy(NearestStrategy, OPMBatchStrategy):
    name = "nearest-batch"
    uses_params = False
    summary = "nearest item per free hand, each seen from where the previous one is taken"


class RandomBatchStrategy(RandomStrategy):
    name = "random-batch"
    summary = "a seeded uniform sample of the remaining items, one per free hand"

    def choose_batch(self, remaining: Sequence[Candidate], agent: Sequence[float],
                     capacity: int) -> list[Candidate]:
        rest, batch = list(remaining), []
        while rest and len(batch) < capacity:
            batch.append(rest.pop(int(self.rng.integers(len(rest))) if len(rest) > 1 else 0))
        return batch


class OptimalBatchStrategy(OptimalStrategy):
    """With one hand (`choose`) it is `optimal`: a trip of one item is a step of its order
    (it was the OPM's greedy choice, which let a red-team user believe they compared
    against an exact plan)."""

    name = "optimal-batch"
    summary = (f"the batch that begins a least-cost plan of trips, exact (up to "
               f"{MAX_OPTIMAL_BATCH_ITEMS} items; one item a trip: as optimal)")

    def choose_batch(self, remaining: Sequence[Candidate], agent: Sequence[float],
                     capacity: int) -> list[Candidate]:
        _, batch = self.plan_trips(remaining, agent, capacity)
        return list(batch[0]) if batch else list(remaining[:1])

    def plan_trips(self, items: Sequence[Candidate], agent: Sequence[float],
                   capacity: int) -> tuple[float, list[tuple[Candidate, ...]]]:
        """The least total cost of fetching every item in trips of at most `capacity`,
        and the trips (each in fetch order). Ties go to the first found (items in their
        given order), so the answer is deterministic."""
        items = list(items)
        n = len(items)
        if n > MAX_OPTIMAL_BATCH_ITEMS:
            raise StrategyError(f"optimal-batch plans exactly for at most "
                                f"{MAX_OPTIMAL_BATCH_ITEMS} items, got {n}; use opm-batch "
                                "for larger tasks")
        self._ensure_weights(items, agent)
        cost, kc = self.model.cost, [self.kc(c) for c in items]

        def c(here: Position, j: int) -> float:
            return cost(here, items[j].position, *kc[j])

        @cache
        def best(mask: int, start: int) -> tuple[float, tuple[tuple[int, ...], ...]]:
            """Least cost of the items in `mask` from after item `start` (-1: the agent)."""
            if mask == 0:
                return 0.0, ()
            here = tuple(agent) if start < 0 else items[start].after_position()
            members = [i for i in range(n) if mask >> i & 1]
            answer: tuple[float, tuple[tuple[int, ...], ...]] = (float("inf"), ())
            for size in range(1, min(capacity, len(members)) + 1):
                for trip in itertools.permutations(members, size):
                    fetch = c(here, trip[0]) + sum(
                        c(items[a].fetch_position(), b) for a, b in itertools.pairwise(trip))
                    rest_mask = mask & ~sum(1 << i for i in trip)
                    # (delivered in fetch order: it ends after the trip's last item)
                    total, trips = best(rest_mask, trip[-1])
                    if fetch + total < answer[0] - 1e-12:
                        answer = (fetch + total, (trip, *trips))
            return answer

        total, trips = best((1 << n) - 1, -1)
        return total, [tuple(items[i] for i in trip) for trip in trips]
