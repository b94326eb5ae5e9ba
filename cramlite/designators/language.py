"""Plan language: sequential composition and try-in-order of alternatives.

Both take zero-argument callables or objects with `perform(ctx)`. `TryInOrder` tries
alternatives until one succeeds; if all fail, the last failure escapes, carrying
everything that was tried.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import PlanFailure

Step = Any  # an action/motion with .perform(ctx), or a callable taking ctx


def _run(step: Step, ctx: RobotContext) -> Any:
    return step.perform(ctx) if hasattr(step, "perform") else step(ctx)


@dataclass
class Sequential:
    """Run steps in order; the first failure stops the sequence."""

    steps: Iterable[Step]

    def perform(self, ctx: RobotContext) -> list[Any]:
        return [_run(step, ctx) for step in self.steps]


@dataclass
class TryInOrder:
    """Run alternatives until one succeeds."""

    alternatives: Iterable[Step]
    describe: Callable[[Step], str] = repr

    def perform(self, ctx: RobotContext) -> Any:
        tried: list[str] = []
        last: PlanFailure | None = None
        for alternative in self.alternatives:
            try:
                return _run(alternative, ctx)
            except PlanFailure as failure:
                tried.append(f"{self.describe(alternative)}: {failure.kind}: {failure.reason}")
                last = failure
        if last is None:
            raise PlanFailure("no alternatives to try")
        raise type(last)(last.reason, obj=last.object, tried=tried)
