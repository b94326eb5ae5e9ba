"""`optimal`: the order of least total weighted cost, planned up front (thesis 3.3.3.2).

Total cost of an order = C(agent, first) + sum over later items of
C(where the agent stands after the previous item, item), with C the OPM's weighted cost
and "where it stands after" the previous item's `then_at` (its target, when the agent
delivers each item before fetching the next) or, without one, the item's position.
Exact dynamic programming over subsets (Held-Karp), O(2^n n^2), vectorised per subset.
If the remaining items ever differ from the plan (a human took another item), it
re-plans from the current position.
"""

from __future__ import annotations

from collections.abc import Sequence

from cramlite.strategies.base import StrategyError
from cramlite.strategies.candidates import Candidate
from cramlite.strategies.opm import OPMStrategy

MAX_OPTIMAL_ITEMS = 15


class OptimalStrategy(OPMStrategy):
    name = "optimal"
    summary = f"least total weighted cost order, exact DP (up to {MAX_OPTIMAL_ITEMS} items)"
    memoryless = False

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._plan: list[Candidate] = []

    def reset(self, candidates: Sequence[Candidate] = (),
              agent: Sequence[float] | None = None) -> None:
        super().reset(candidates, agent)
        self._plan = []

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        if sorted(c.name for c in self._plan) != sorted(c.name for c in remaining):
            self._plan = self.plan(remaining, agent)
        nxt = self._plan.pop(0)
        same = [c for c in remaining if c.name == nxt.name]
        return min(same, key=lambda c: sum((a - b) ** 2 for a, b in
                                           zip(c.position, nxt.position, strict=True)))

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        return [self.choose(remaining, agent)]

    def plan(self, items: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        """The full order of least total cost from `agent` over `items`."""
        import numpy as np  # here, not at module level: listing strategies stays fast

        n = len(items)
        if n > MAX_OPTIMAL_ITEMS:
            raise StrategyError(f"optimal plans exactly for at most {MAX_OPTIMAL_ITEMS} items, "
                                f"got {n}; use opm or opm-2step for larger tasks")
        if n == 1:
            return list(items)
        self._ensure_weights(items, agent)
        kc = np.array([self.kc(c) for c in items], dtype=float)
        positions = np.array([c.position for c in items], dtype=float)
        start = self.model.costs(agent, positions, kc[:, 0], kc[:, 1])
        step = np.vstack([self.model.costs(c.after_position(), positions, kc[:, 0], kc[:, 1])
                          for c in items])  # step[i, j]: after i, fetch j
        np.fill_diagonal(step, np.inf)
        full = 1 << n
        dp = np.full((full, n), np.inf)
        parent = np.full((full, n), -1, dtype=np.int64)
        bits = 1 << np.arange(n)
        dp[bits, np.arange(n)] = start
        for mask in range(1, full):
            row = dp[mask]
            if not np.isfinite(row).any():
                continue
            nxt = np.flatnonzero((mask & bits) == 0)
            if nxt.size == 0:
                continue
            total = row[:, None] + step[:, nxt]
            best_last = total.argmin(axis=0)
            value = total[best_last, np.arange(nxt.size)]
            new_masks = mask | bits[nxt]
            better = value < dp[new_masks, nxt]
            dp[new_masks[better], nxt[better]] = value[better]
            parent[new_masks[better], nxt[better]] = best_last[better]
        final = dp[full - 1]
        ends = np.flatnonzero(final == final.min())
        if len(ends) > 1:
            self.random_picks += 1
        last = int(ends[0] if len(ends) == 1 else ends[self.rng.integers(len(ends))])
        order, mask = [], full - 1
        while last >= 0:
            order.append(last)
            last, mask = int(parent[mask, last]), mask & ~(1 << last)
        return [items[i] for i in reversed(order)]

    def total_cost(self, order: Sequence[Candidate], agent: Sequence[float]) -> float:
        """Total weighted cost of a given order (for checking plans)."""
        total, here = 0.0, tuple(agent)
        for c in order:
            total += self.model.cost(here, c.position, *self.kc(c))
            here = c.after_position()
        return total
