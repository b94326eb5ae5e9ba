"""The strategy interface: given the remaining candidates and where the agent stands,
return the candidate to fetch next.

A strategy object lives for one episode (one trial, one human sequence): `reset`
starts a new one. Every random choice goes through `self.rng`, a numpy Generator the
caller seeds. Memoryless strategies also expose `tied`, the set they choose uniformly
from, which exact metrics (expected APE) use instead of sampling.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from cramlite.strategies.candidates import Candidate, OPMParams
from cramlite.strategies.cost import CostModel, span_weights


class StrategyError(ValueError):
    """A strategy was asked for something it cannot do (bad name, too many items...)."""


def as_generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


class Strategy(ABC):
    """Base class of ordering strategies (subclass it for a plugin)."""

    name: ClassVar[str] = "strategy"
    summary: ClassVar[str] = ""
    #: True when the choice depends only on (remaining, agent): `tied` is then exact.
    memoryless: ClassVar[bool] = True
    #: False when OPM parameters (k, c) do not change the choice (fits skip the grid).
    uses_params: ClassVar[bool] = True

    def __init__(self, params: Mapping[str, float] | None = None, *, dims: str = "xy",
                 form: str = "power",
                 axis_weights: tuple[float, float, float] | str | None = None,
                 rng: np.random.Generator | int | None = None, **options: Any):
        try:
            self.params = OPMParams.from_mapping(params)
        except KeyError as exc:
            raise StrategyError(f"unknown parameter {exc.args[0]!r}; expected some of "
                                f"{', '.join(OPMParams.names())}") from None
        self._span_weights = axis_weights == "span"
        weights = None if isinstance(axis_weights, str) else axis_weights
        try:
            self.model = CostModel(dims=dims, form=form, axis_weights=weights)
        except ValueError as exc:
            raise StrategyError(str(exc)) from None
        self.rng = as_generator(rng)
        self.options = options
        #: How many choices were made at random among more than one option.
        self.random_picks = 0

    # -- episode lifecycle ---------------------------------------------------------------
    def reset(self, candidates: Sequence[Candidate] = (),
              agent: Sequence[float] | None = None) -> None:
        """Start a new episode; with span weights, fix them from all its positions."""
        if self._span_weights and candidates:
            points = [c.position for c in candidates] + ([tuple(agent)] if agent else [])
            self.model = CostModel(self.model.dims, self.model.form, span_weights(points))

    # -- decisions -----------------------------------------------------------------------
    @abstractmethod
    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        """The candidate to fetch next (remaining is non-empty)."""

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        """The candidates this strategy would choose uniformly among (memoryless ones)."""
        return [self.choose(remaining, agent)]

    def costs(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[float] | None:
        """Weighted costs of the remaining candidates, if the strategy has any."""
        return None

    def _pick(self, tied: Sequence[Candidate]) -> Candidate:
        if len(tied) == 1:
            return tied[0]
        self.random_picks += 1
        return tied[int(self.rng.integers(len(tied)))]

    def _ensure_weights(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> None:
        if self._span_weights and self.model.axis_weights is None:
            self.reset(remaining, agent)
