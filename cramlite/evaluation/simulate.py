"""Synthetic episodes drawn from a strategy: the check that a fitting procedure recovers
the parameters that generated the data (parameter recovery).

Each synthetic episode copies one recorded episode's task (the same items at the same
positions, categories and storage, the subject's same start position before each step)
and draws a new order from the model. The choice rule is a softmax over the costs:
P(item) is proportional to exp(-cost / temperature), so a low temperature takes the
lowest-cost item almost always (temperature 0: always, ties broken uniformly at random,
which is the OPM itself) and a high one approaches random guessing. The episodes are
written in the published format (an `activity` column keeps each copy's activity), so
`fit`, `evaluate` and `compare` read them like recorded ones.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cramlite.errors import UserInputError
from cramlite.evaluation.data import CATEGORY_COLUMNS, Episode
from cramlite.evaluation.options import DEFAULT_TEMPERATURE
from cramlite.strategies.candidates import Candidate
from cramlite.strategies.opm import OPMStrategy
from cramlite.strategies.registry import make_strategy

COLUMNS = ("ID", "sequence", "coordinates", "start_coordinates", *CATEGORY_COLUMNS,
           "containment", "error", "activity")


@dataclass(frozen=True)
class SimulatedEpisode:
    """One drawn order of a recorded episode's items."""

    source: Episode
    id: str
    order: tuple[Candidate, ...]


def softmax_choice(costs: Sequence[float], temperature: float,
                   rng: np.random.Generator) -> int:
    """An index drawn with P proportional to exp(-cost / temperature) (0: the argmin,
    ties uniformly)."""
    values = np.asarray(costs, dtype=float)
    if temperature <= 0:
        ties = np.flatnonzero(values == values.min())
        return int(ties[rng.integers(len(ties))]) if len(ties) > 1 else int(ties[0])
    weights = np.exp(-(values - values.min()) / temperature)
    return int(rng.choice(len(values), p=weights / weights.sum()))


def cost_strategy(strategy: str, params: Mapping[str, float] | None, dims: str,
                  form: str) -> OPMStrategy:
    """The strategy whose costs drive the softmax (an OPM-family strategy)."""
    model = make_strategy(strategy, params=params, dims=dims, form=form)
    if not isinstance(model, OPMStrategy):
        raise UserInputError(f"expected a strategy with a cost per item (opm, nearest or "
                             f"a subclass of the OPM), got {strategy!r}", field="--strategy")
    return model


def simulate(like: Sequence[Episode], count: int, strategy: str = "opm",
             params: Mapping[str, float] | None = None, temperature: float = DEFAULT_TEMPERATURE,
             seed: int = 0, dims: str = "xy", form: str = "power") -> list[SimulatedEpisode]:
    """`count` episodes, the j-th a new order of `like[j % len(like)]`'s items. Episode j
    draws from `default_rng([seed, j])`, so the episodes do not depend on `count`."""
    if not like:
        raise UserInputError("no episodes to copy the tasks from", field="--like")
    if count < 1:
        raise UserInputError(f"expected at least 1 episode, got {count}", field="--episodes")
    if not math.isfinite(temperature) or temperature < 0:
        raise UserInputError(f"expected a temperature >= 0, got {temperature}",
                             field="--temperature")
    model = cost_strategy(strategy, params, dims, form)
    out = []
    for j in range(count):
        source = like[j % len(like)]
        rng = np.random.default_rng([seed, j])
        remaining = list(source.sequence_items())
        order = []
        for step in range(len(source)):
            costs = model.costs(remaining, source.start_positions[step])
            order.append(remaining.pop(softmax_choice(costs, temperature, rng)))
        out.append(SimulatedEpisode(source, f"sim{j:04d}-{source.id}", tuple(order)))
    return out


def _position(p: Sequence[float]) -> str:
    return ",".join(repr(float(v)) for v in p)


def episode_row(episode: SimulatedEpisode) -> dict[str, str]:
    """The published format. Coordinates list the taken instances in the order taken (a
    repeated name's j-th occurrence is its j-th listed instance when read back), then the
    recorded episode's items that were not taken."""
    source = episode.source
    taken_ids = {id(c) for c in episode.order}
    listed = [*episode.order, *(c for c in source.items if id(c) not in taken_ids)]
    return {"ID": episode.id,
            "sequence": ",".join(c.name for c in episode.order),
            "coordinates": ";".join(f"{c.name}: ({_position(c.position)})" for c in listed),
            "start_coordinates": ",".join(f"[{_position(p)}]" for p in source.start_positions),
            **{column: source.cells.get(column, "") for column in CATEGORY_COLUMNS},
            "containment": source.cells.get("containment", ""),
            "error": "" if source.published_baseline is None else repr(source.published_baseline),
            "activity": source.activity}


def write_episodes(episodes: Sequence[SimulatedEpisode], path: Path) -> None:
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        for episode in episodes:
            writer.writerow(episode_row(episode))
