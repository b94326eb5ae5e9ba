"""The Opportunistic Planning Model and its relatives (thesis 3.1 and 3.3.3).

`opm`: next = argmin over remaining items of C(agent, item) (Eq. 3.1 by default),
ties broken uniformly at random. `nearest`: the same with k = c = 1 (plain distance).
`opm-2step`: choose the best item and commit to the best item after it, seen from where
the agent will stand after the first (its `then_at`, e.g. its target on the table).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from cramlite.strategies.base import Strategy
from cramlite.strategies.candidates import Candidate

if TYPE_CHECKING:  # numpy only where the vectorised paths use it (fast start-up)
    import numpy as np

#: Above this many candidates the numpy path is faster than plain Python.
VECTOR_THRESHOLD = 48


class OPMStrategy(Strategy):
    name = "opm"
    summary = "Opportunistic Planning Model: argmin d^k * c from the agent (Eq. 3.1)"

    def kc(self, candidate: Candidate) -> tuple[float, float]:
        return self.params.k_of(candidate), self.params.c_of(candidate)

    def costs(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[float]:
        self._ensure_weights(remaining, agent)
        if len(remaining) > VECTOR_THRESHOLD:
            import numpy as np

            kc = np.array([self.kc(c) for c in remaining], dtype=float)
            positions = np.array([c.position for c in remaining], dtype=float)
            return self.model.costs(agent, positions, kc[:, 0], kc[:, 1]).tolist()
        cost = self.model.cost
        return [cost(agent, c.position, *self.kc(c)) for c in remaining]

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        values = self.costs(remaining, agent)
        best = min(values)
        return [c for c, v in zip(remaining, values, strict=True) if v == best]

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        return self.greedy(remaining, agent)

    def greedy(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        """The lowest-cost candidate, ties broken uniformly at random."""
        return self._pick(OPMStrategy.tied(self, remaining, agent))

    def choose_index(self, agent: Sequence[float], positions: np.ndarray,
                     k: np.ndarray | float, c: np.ndarray | float) -> int:
        """Vectorised decision over arrays (N x 3 positions): the index of the next item."""
        import numpy as np

        values = self.model.costs(agent, positions, k, c)
        ties = np.flatnonzero(values == values.min())
        return int(ties[0] if len(ties) == 1 else ties[self.rng.integers(len(ties))])


class NearestStrategy(OPMStrategy):
    name = "nearest"
    uses_params = False
    summary = "plain distance: the OPM with k = c = 1"

    def kc(self, candidate: Candidate) -> tuple[float, float]:
        return 1.0, 1.0


class OPMTwoStepStrategy(OPMStrategy):
    name = "opm-2step"
    summary = "2-step OPM: best item now, and commit to the best one after it (3.3.3.1)"
    memoryless = False

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._committed: Candidate | None = None

    def reset(self, candidates: Sequence[Candidate] = (),
              agent: Sequence[float] | None = None) -> None:
        super().reset(candidates, agent)
        self._committed = None

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        committed = self._take_commitment(remaining)
        if committed is not None:
            return committed
        first = self.greedy(remaining, agent)
        rest = [c for c in remaining if c is not first]
        if rest:
            self._committed = self.greedy(rest, first.after_position())
        return first

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        return [self.choose(remaining, agent)]

    def _take_commitment(self, remaining: Sequence[Candidate]) -> Candidate | None:
        """The committed item if it is still there (matched by name, then nearest position:
        positions read back from a simulation may differ in the last digits)."""
        target, self._committed = self._committed, None
        if target is None:
            return None
        same = [c for c in remaining if c.name == target.name]
        if not same:
            return None
        return min(same, key=lambda c: sum((a - b) ** 2 for a, b in
                                           zip(c.position, target.position, strict=True)))
