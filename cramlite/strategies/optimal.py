"""`optimal`: the order of least total weighted cost, planned up front (thesis 3.3.3.2).

Total cost of an order = C(agent, first) + sum over later items of
C(where the agent stands after the previous item, item), with C the OPM's weighted cost
and "where it stands after" the previous item's `then_at` (its target, when the agent
delivers each item before fetching the next) or, without one, the item's position.
Exact dynamic programming over subsets (Held-Karp), O(2^n n^2), vectorised per subset
size. It re-plans at every decision from where the agent stands and takes, uniformly
among ties, an item that begins a least-cost order: by Bellman's principle that is the
order planned up front while the agent is where the plan expects it, it copes when it is
not (a human took another item), and each decision depends only on what is left, so
exact expected APE and the vectorised fit apply. When every item's `then_at` is the
same point T (every trip starts at the table), the order after the first does not
matter, and the first item minimises C(agent, j) - C(T, j).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from cramlite.strategies.base import StrategyError
from cramlite.strategies.candidates import Candidate
from cramlite.strategies.opm import OPMStrategy

if TYPE_CHECKING:  # numpy is imported where it is used (`strategies` starts fast)
    import numpy as np

MAX_OPTIMAL_ITEMS = 15
#: Totals within this relative distance of the least are ties (sums of the same costs in
#: another order differ in the last bits).
TIE_RTOL = 1e-12


def completion_costs(step: np.ndarray) -> np.ndarray:
    """rest[mask, i]: least cost of fetching every item in `mask` (a bit set over n items),
    starting from where the agent stands after item i (i not in mask); `step[i, j]` is the
    cost of fetching j after i. Held-Karp backwards, one layer of subset sizes at a time."""
    import numpy as np

    n = step.shape[0]
    full = 1 << n
    rest = np.full((full, n), np.inf)
    rest[0] = 0.0
    sizes = np.array([bin(m).count("1") for m in range(full)])
    bits = 1 << np.arange(n)
    for size in range(1, n + 1):
        masks = np.flatnonzero(sizes == size)
        member = (masks[:, None] & bits[None, :]) != 0  # (M, n): l in mask
        # total[m, i, l] = step[i, l] + rest[mask - l, l]
        without = rest[masks[:, None] ^ bits[None, :], np.arange(n)[None, :]]  # (M, n)
        total = step[None, :, :] + without[:, None, :]
        total = np.where(member[:, None, :], total, np.inf)
        rest[masks] = total.min(axis=2)
    return rest


class OptimalStrategy(OPMStrategy):
    name = "optimal"
    summary = f"least total weighted cost order, exact DP (up to {MAX_OPTIMAL_ITEMS} items)"

    def first_costs(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> np.ndarray:
        """For each item, the least total cost of an order that starts with it, up to a
        constant shared by all items (what decides the first item)."""
        import numpy as np

        n = len(remaining)
        self._ensure_weights(remaining, agent)
        kc = np.array([self.kc(c) for c in remaining], dtype=float).reshape(-1, 2)
        positions = np.array([c.position for c in remaining], dtype=float).reshape(-1, 3)
        start = self.model.costs(agent, positions, kc[:, 0], kc[:, 1])
        afters = {c.after_position() for c in remaining}
        if len(afters) == 1:  # every trip starts from one point (e.g. the table)
            return start - self.model.costs(afters.pop(), positions, kc[:, 0], kc[:, 1])
        if n > MAX_OPTIMAL_ITEMS:
            raise StrategyError(f"{self.name} plans exactly for at most {MAX_OPTIMAL_ITEMS} items, "
                                f"got {n}; use opm or opm-2step for larger tasks")
        step = np.vstack([self.model.costs(c.after_position(), positions, kc[:, 0], kc[:, 1])
                          for c in remaining])  # step[i, j]: after i, fetch j
        rest = completion_costs(step)
        full = (1 << n) - 1
        return start + np.array([rest[full ^ (1 << j), j] for j in range(n)])

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        values = self.first_costs(remaining, agent)
        best = values.min()
        close = values <= best + TIE_RTOL * max(abs(best), 1.0)
        return [c for c, near in zip(remaining, close, strict=True) if near]

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        return self._pick(self.tied(remaining, agent))

    def plan(self, items: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        """A full order of least total cost from `agent` over `items`."""
        remaining, order, here = list(items), [], tuple(agent)
        while remaining:
            chosen = self.choose(remaining, here)
            order.append(chosen)
            remaining.remove(chosen)
            here = chosen.after_position()
        return order

    def total_cost(self, order: Sequence[Candidate], agent: Sequence[float]) -> float:
        """Total weighted cost of a given order (for checking plans)."""
        total, here = 0.0, tuple(agent)
        for c in order:
            total += self.model.cost(here, c.position, *self.kc(c))
            here = c.after_position()
        return total
