"""Farthest first: a strategy written in a file (the README's "swap the strategy").

    cramlite run v1 --strategy ./examples/farthest_first.py:FarthestFirst
    cramlite bench --setups v1 --strategies opm,./examples/farthest_first.py:FarthestFirst

A strategy is a `cramlite.Strategy` with a `choose(remaining, agent)`: the candidate to
fetch next, from the items not fetched yet (each a `Candidate` with its `position`,
`category`, `contained` flag, ...) and the robot's position `agent` (x, y, z).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from cramlite import Candidate, Strategy


class FarthestFirst(Strategy):
    """The item farthest from the robot first (the opposite of the OPM's nearest)."""

    name = "farthest-first"
    uses_params = False
    summary = "the item farthest from the robot first"

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        return max(remaining, key=lambda c: math.dist(c.position[:2], agent[:2]))
