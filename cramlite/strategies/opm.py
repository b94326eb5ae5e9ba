"""The Opportunistic Planning Model and its relatives (thesis 3.1 and 3.3.3).

`opm`: next = argmin over remaining items of C(agent, item) (Eq. 3.1 by default),
ties broken uniformly at random. `nearest`: the same with k = c = 1 (plain distance).
`opm-2step`: choose the best item and commit to the best item after it, seen from where
the first one is taken (its `fetch_at`, by default its position).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from cramlite.strategies.base import Strategy
from cramlite.strategies.candidates import Candidate
from cramlite.strategies.history import TakenHistory

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


class OPMTwoStepStrategy(TakenHistory, OPMStrategy):
    """The 2-step model (3.3.3.1): decisions come in pairs. The first of a pair is the
    OPM's choice from where the agent stands; the second is chosen "directly when
    performing the first action": the lowest-cost remaining item as seen from where the
    first was taken (its `fetch_at`, by default the item's position), and it is taken
    next whatever is cheapest from where the agent then stands.

    When a caller reports with `observe` that another item was taken (teacher-forced
    scoring of human sequences), the second choice is made from where that one was taken.
    """

    name = "opm-2step"
    summary = "2-step OPM: best item now, and the best one as seen from it next (3.3.3.1)"
    memoryless = False

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.reset_history()

    def reset(self, candidates: Sequence[Candidate] = (),
              agent: Sequence[float] | None = None) -> None:
        super().reset(candidates, agent)
        self.reset_history()

    def decision_point(self, agent: Sequence[float]) -> Sequence[float]:
        """Where this step's costs are measured from: the agent for the first of a pair,
        where the pair's first item was taken for the second."""
        if len(self.taken) % 2 == 1:
            return self.taken[-1].fetch_position()
        return agent

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        return OPMStrategy.tied(self, remaining, self.decision_point(agent))

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        chosen = self._pick(self.tied(remaining, agent))
        self.record_choice(chosen)
        return chosen
