"""The strategy interface: given the remaining candidates and where the agent stands,
return the candidate to fetch next.

A strategy object lives for one episode (one trial, one human sequence): `reset`
starts a new one. Every random choice goes through `self.rng`, a numpy Generator the
caller seeds; it is created on first use (only a tie needs it), so a decision over a few
items runs in plain Python without importing numpy. Memoryless strategies also expose
`tied`, the set they choose uniformly from, which exact metrics (expected APE) use
instead of sampling.
"""

from __future__ import annotations

import contextlib
import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar

from cramlite.strategies.candidates import Candidate, OPMParams
from cramlite.strategies.cost import CostModel, span_weights

if TYPE_CHECKING:
    import numpy as np

#: Accepted ranges of the OPM's parameters (k per item or category, containment c).
#: The source's grid spans k 0.0-2.0 and c 1.0-2.0; the bounds keep every cost finite
#: for coordinates up to MAX_COORDINATE_M.
K_RANGE = (0.0, 10.0)
C_RANGE = (0.0, 1000.0)  # exclusive at 0: c scales the cost
MAX_COORDINATE_M = 1e6


class StrategyError(ValueError):
    """A strategy was asked for something it cannot do (bad name, too many items...)."""


class StrategyCrashed(StrategyError):
    """A strategy raised something else than a StrategyError, or returned something that
    is not a candidate: a bug in it, not a case it cannot handle (evaluations stop)."""


def as_generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    import numpy as np

    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def parameter_problem(name: str, value: Any) -> str | None:
    """Why `value` is not acceptable for the OPM parameter `name` (a k or c), else None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"expected a number, got {value!r}"
    try:
        number = float(value)
    except OverflowError:
        return f"expected a number of ordinary size, got one with {len(str(value))} digits"
    is_c = name == "c" or name.endswith(".c")
    low, high = C_RANGE if is_c else K_RANGE
    if not math.isfinite(number) or number > high or number < low or (is_c and number == low):
        interval = f"in ({low:g}, {high:g}]" if is_c else f"in [{low:g}, {high:g}]"
        return f"expected a finite number {interval}, got {value!r}"
    return None


def check_params(params: OPMParams) -> None:
    """Raise StrategyError if a parameter is out of range (negative k, c <= 0, NaN...)."""
    for name in OPMParams.names():
        problem = parameter_problem(name, getattr(params, name))
        if problem:
            raise StrategyError(f"parameter {name}: {problem}")


def strategy_label(strategy: Strategy) -> str:
    """How to name a strategy in an error: its registered name and its class."""
    cls = type(strategy)
    where = cls.__module__
    if where.startswith("_cramlite_user_"):  # (a file loaded by its path: name the file)
        import inspect

        with contextlib.suppress(TypeError, OSError):
            where = inspect.getfile(cls)
        place = f"{where}:{cls.__qualname__}"
    else:
        place = f"{where}.{cls.__qualname__}"
    # (a class that sets no name of its own has Strategy's: its place alone names it)
    return place if cls.name == Strategy.name else f"{cls.name!r} ({place})"


def checked_reset(strategy: Strategy, candidates: Sequence[Candidate],
                  agent: Sequence[float]) -> None:
    """`strategy.reset(candidates, agent)`, checked like `checked_choice`: a plugin that
    raises becomes a StrategyError naming it."""
    try:
        strategy.reset(candidates, agent)
    except StrategyError:
        raise
    except Exception as exc:
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} raised "
                              f"{type(exc).__name__} when reset: {exc}") from exc


def checked_tied(strategy: Strategy, remaining: Sequence[Candidate],
                 agent: Sequence[float]) -> list[Candidate]:
    """`strategy.tied(remaining, agent)`, checked like `checked_choice`."""
    try:
        tied = list(strategy.tied(remaining, agent))
    except StrategyError:
        raise
    except Exception as exc:
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} raised "
                              f"{type(exc).__name__}: {exc}") from exc
    if not tied or not all(any(c is t or c == t for c in remaining) for t in tied):
        shown = repr(tied)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} returned {shown} as its "
                              "tied choices; expected some of the remaining candidates")
    return tied


def checked_choice(strategy: Strategy, remaining: Sequence[Candidate],
                   agent: Sequence[float]) -> Candidate:
    """`strategy.choose(remaining, agent)`, checked: the one place where a misbehaving
    strategy (a plugin that raises, returns None or something that is not one of the
    remaining candidates) becomes a StrategyError naming it. A StrategyError the
    strategy raises itself (e.g. too many items for `optimal`) passes unchanged."""
    try:
        choice = strategy.choose(remaining, agent)
    except StrategyError:
        raise
    except Exception as exc:
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} raised "
                              f"{type(exc).__name__}: {exc}") from exc
    for candidate in remaining:
        if candidate is choice:
            return candidate
    for candidate in remaining:  # an equal copy is fine too
        if isinstance(choice, Candidate) and candidate == choice:
            return candidate
    shown = repr(choice)
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    raise StrategyCrashed(f"strategy {strategy_label(strategy)} returned {shown} "
                        f"({type(choice).__name__}); expected one of the {len(remaining)} "
                        "remaining candidates")


def checked_batch(strategy: Strategy, remaining: Sequence[Candidate], agent: Sequence[float],
                  capacity: int) -> list[Candidate]:
    """`strategy.choose_batch(remaining, agent, capacity)`, checked like `checked_choice`:
    between one and `capacity` distinct remaining candidates (an equal copy is fine)."""
    if capacity == 1:
        return [checked_choice(strategy, remaining, agent)]
    try:
        batch = list(strategy.choose_batch(remaining, agent, capacity))
    except StrategyError:
        raise
    except Exception as exc:
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} raised "
                              f"{type(exc).__name__} choosing a batch: {exc}") from exc
    found = []
    for choice in batch:
        match = next((c for c in remaining if c is choice), None) or next(
            (c for c in remaining if isinstance(choice, Candidate) and c == choice), None)
        if match is None or match in found:
            found = []
            break
        found.append(match)
    if not found or len(found) > capacity:
        shown = repr(batch)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise StrategyCrashed(f"strategy {strategy_label(strategy)} returned {shown} as its "
                              f"batch; expected 1 to {capacity} distinct remaining candidates")
    return found


class CheckedStrategy:
    """A strategy as a user's plan is given it: `choose`, `reset`, `choose_batch` and
    `tied` checked as the built-in plans check them (`checked_choice`, ...), so a plugin
    that returns None or raises is a StrategyError naming it, not an AttributeError deep
    in the plan; everything else is the strategy's own (`.strategy` is the strategy)."""

    def __init__(self, strategy: Strategy):
        self.strategy = strategy

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        return checked_choice(self.strategy, remaining, agent)

    def reset(self, candidates: Sequence[Candidate], agent: Sequence[float]) -> None:
        checked_reset(self.strategy, candidates, agent)

    def choose_batch(self, remaining: Sequence[Candidate], agent: Sequence[float],
                     capacity: int) -> list[Candidate]:
        return checked_batch(self.strategy, remaining, agent, capacity)

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        return checked_tied(self.strategy, remaining, agent)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.strategy, name)

    def __repr__(self) -> str:
        return f"CheckedStrategy({self.strategy!r})"


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
        except (TypeError, ValueError, OverflowError) as exc:
            raise StrategyError(f"parameters: expected numbers ({exc})") from None
        check_params(self.params)
        self._span_weights = axis_weights == "span"
        weights = None if isinstance(axis_weights, str) else axis_weights
        try:
            self.model = CostModel(dims=dims, form=form, axis_weights=weights)
        except ValueError as exc:
            raise StrategyError(str(exc)) from None
        self._rng = rng
        self.options = options
        #: How many choices were made at random among more than one option.
        self.random_picks = 0

    @property
    def rng(self) -> np.random.Generator:
        """The strategy's generator, made from the seed it was given on first use."""
        if not hasattr(self._rng, "integers"):  # a seed (None, int, list), not a Generator
            self._rng = as_generator(self._rng)
        return self._rng  # type: ignore[return-value]

    @rng.setter
    def rng(self, value: np.random.Generator | int | None) -> None:
        self._rng = value

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

    def choose_batch(self, remaining: Sequence[Candidate], agent: Sequence[float],
                     capacity: int) -> list[Candidate]:
        """The items to carry together on the next trip, in the order they are fetched (at
        most `capacity`, at least one). By default `choose` is asked once per free hand,
        each time from where the agent stands now: every strategy and plugin keeps
        working. The batch strategies (`opm-batch`...) answer this themselves."""
        rest, batch = list(remaining), []
        while rest and len(batch) < capacity:
            chosen = checked_choice(self, rest, agent)
            batch.append(chosen)
            rest.remove(chosen)
        return batch

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
