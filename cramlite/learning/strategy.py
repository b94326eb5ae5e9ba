"""`learned:MODEL`: a trained model as an ordering strategy (evaluation, robot, bench).

At each decision the model scores every item it knows from what was taken so far (and,
for the NN, the context); the strategy takes the best-scored remaining item, ties broken
by the seeded generator. A candidate is matched to the model's vocabulary by its name,
then its `aliases`, then its `type` (both from `Candidate.metadata`, which the robot's
plans fill from the setup). Items the model never saw are never preferred to known
ones; when no remaining item is known, one is taken uniformly at random.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, ClassVar

import numpy as np

from cramlite.learning.encoding import token_of
from cramlite.learning.modelfile import LearnedModel, load_model
from cramlite.strategies.base import Strategy
from cramlite.strategies.candidates import Candidate
from cramlite.strategies.history import TakenHistory

PREFIX = "learned:"
#: The thesis's RNN sampled its output divided by 0.4 (a temperature).
THESIS_TEMPERATURE = 0.4


class LearnedStrategy(TakenHistory, Strategy):
    name = "learned"
    summary = "a model trained by `cramlite train` (name it learned:MODEL_FILE)"
    memoryless = False
    uses_params = False
    model_path: ClassVar[str] = ""

    def __init__(self, *args: Any, model: str | None = None, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self.learned: LearnedModel = load_model(model or self.model_path)
        self.reset_history()

    def reset(self, candidates: Sequence[Candidate] = (),
              agent: Sequence[float] | None = None) -> None:
        super().reset(candidates, agent)
        self.reset_history()

    def _known(self, remaining: Sequence[Candidate]) -> list[tuple[Candidate, str | None]]:
        index = self.learned.index
        return [(c, token_of(c, index)) for c in remaining]

    def tied(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> list[Candidate]:
        pairs = self._known(remaining)
        known = [(c, t) for c, t in pairs if t is not None]
        if not known:
            return list(remaining)
        index = self.learned.index
        history = [t for t in (token_of(c, index) for c in self.taken) if t is not None]
        scores = self.learned.scores(history, [replace(c, name=t) for c, t in known], agent)
        values = np.array([scores[index[t]] for _, t in known])
        best = values.max()
        return [c for (c, _), v in zip(known, values, strict=True) if v == best]

    def choose(self, remaining: Sequence[Candidate], agent: Sequence[float]) -> Candidate:
        chosen = self._pick(self.tied(remaining, agent))
        self.record_choice(chosen)
        return chosen


@functools.cache
def learned_class(path: str) -> type[LearnedStrategy]:
    """A strategy class bound to one model file (checked now: a bad file fails early)."""
    load_model(path)
    return type("LearnedModelStrategy", (LearnedStrategy,),
                {"model_path": path, "name": f"{PREFIX}{path}"})
