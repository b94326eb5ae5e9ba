"""The plan language (PyCRAM's, on cramlite's designators).

Every construct takes steps: objects with `perform(ctx)` (actions, motions, other
constructs) or callables taking the context. Each becomes a node of the task tree with
its status and robot-time span.

- `Sequential(steps)`: in order; the first failure stops it.
- `TryInOrder(alternatives)`: until one succeeds; if all fail, the last failure escapes,
  carrying everything that was tried.
- `TryAll(steps)`: every step, whatever the others did; succeeds if one did (the results,
  None for a failed step); if all fail, as `TryInOrder`.
- `Parallel(steps)`: all of them; until combined motions exist (the parallel-motion
  issue) they run one after another, in order, every one even when another failed; the
  first failure escapes after all ran.
- `Repeat(step, times)`: the step `times` times (a failure stops it).
- `Code(function)`: a Python function of the context as a node of its own.
- `Retry(step, attempts, on_failure)` (or `retry(step, n)`): up to `attempts` tries; before
  each new try `on_failure(ctx, failure)` may recover (park the arms, put down what is
  held), and the scene observes the world again, so the next try plans on what the
  process modules report, never on the belief the failure left (a poisoned state).
- `Monitor(condition, step)`: the condition is asked at every state of every motion
  while the step runs (`cramlite.designators.monitors`); when it holds, the motion brakes
  to rest within the limits and `MonitorFired` escapes.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import PlanFailure
from cramlite.designators.monitors import Condition, MonitorFired, Watch

Step = Any  # an action/motion with .perform(ctx), or a callable taking ctx


def _run(step: Step, ctx: RobotContext) -> Any:
    return step.perform(ctx) if hasattr(step, "perform") else step(ctx)


@contextlib.contextmanager
def _node(ctx: RobotContext | None, name: str) -> Iterator[None]:
    """A node of the task tree (none without a context: a plain function call)."""
    tasks = getattr(ctx, "tasks", None)
    if tasks is None:
        yield
        return
    with tasks.node(name):
        yield


def _all_failed(failures: list[tuple[str, PlanFailure]]) -> PlanFailure:
    if not failures:
        return PlanFailure("no alternatives to try")
    tried = [f"{label}: {failure.kind}: {failure.reason}" for label, failure in failures]
    last = failures[-1][1]
    return type(last)(last.reason, obj=last.object, tried=tried)


@dataclass
class Sequential:
    """Run steps in order; the first failure stops the sequence."""

    steps: Iterable[Step]

    def perform(self, ctx: RobotContext) -> list[Any]:
        with _node(ctx, "Sequential"):
            return [_run(step, ctx) for step in self.steps]


@dataclass
class TryInOrder:
    """Run alternatives until one succeeds."""

    alternatives: Iterable[Step]
    describe: Callable[[Step], str] = repr

    def perform(self, ctx: RobotContext) -> Any:
        failures: list[tuple[str, PlanFailure]] = []
        with _node(ctx, "TryInOrder"):
            for alternative in self.alternatives:
                try:
                    return _run(alternative, ctx)
                except MonitorFired:
                    raise  # (a monitor stops the alternatives too)
                except PlanFailure as failure:
                    failures.append((self.describe(alternative), failure))
            raise _all_failed(failures)


@dataclass
class TryAll:
    """Run every step; succeed if at least one did."""

    steps: Iterable[Step]
    describe: Callable[[Step], str] = repr

    def perform(self, ctx: RobotContext) -> list[Any]:
        results: list[Any] = []
        failures: list[tuple[str, PlanFailure]] = []
        with _node(ctx, "TryAll"):
            for step in self.steps:
                try:
                    results.append(_run(step, ctx))
                except MonitorFired:
                    raise
                except PlanFailure as failure:
                    failures.append((self.describe(step), failure))
                    results.append(None)
            if results and len(failures) == len(results):
                raise _all_failed(failures)
        return results


@dataclass
class Parallel:
    """All steps; every one runs, and the first failure escapes afterwards. A joint motion
    (the torso, an arm) of a step before a step that drives runs *with* that drive, as one
    combined motion checked as one (so `Parallel([MoveTorsoAction(0.25),
    NavigateAction(goal)])` takes the longer of the two); other motions run one after the
    other, and whatever waits for a drive that does not come runs when the steps are done.
    (`while_driving=True` on MoveTorsoAction, ParkArmsAction and MoveArmJointsMotion asks
    for the same outside a Parallel.)"""

    steps: Iterable[Step]

    def perform(self, ctx: RobotContext) -> list[Any]:
        results: list[Any] = []
        first: PlanFailure | None = None
        with _node(ctx, "Parallel"), ctx.deferring():
            for step in self.steps:
                try:
                    results.append(_run(step, ctx))
                except MonitorFired:
                    raise
                except PlanFailure as failure:
                    first = first or failure
                    results.append(None)
            if first is not None:
                raise first
        return results


@dataclass
class Repeat:
    """Run a step `times` times; a failure stops it."""

    step: Step
    times: int

    def __post_init__(self) -> None:  # (refused where the plan writes it)
        if isinstance(self.times, bool) or not isinstance(self.times, int) or self.times < 0:
            raise ValueError(f"Repeat: times must be a whole number >= 0, got {self.times!r}")

    def perform(self, ctx: RobotContext) -> list[Any]:
        with _node(ctx, "Repeat"):
            return [_run(self.step, ctx) for _ in range(self.times)]


@dataclass
class Code:
    """A Python function of the context, as a node of the task tree."""

    function: Callable[[RobotContext], Any]
    name: str = ""

    def perform(self, ctx: RobotContext) -> Any:
        with _node(ctx, f"Code({self.name or getattr(self.function, '__name__', 'code')})"):
            return self.function(ctx)


Recovery = Callable[[RobotContext, PlanFailure], Any]


@dataclass
class Retry:
    """Up to `attempts` tries of a step; between them `on_failure` recovers and the scene
    observes the world again."""

    step: Step
    attempts: int = 2
    on_failure: Recovery | None = None

    def __post_init__(self) -> None:  # (refused where the plan writes it)
        if isinstance(self.attempts, bool) or not isinstance(self.attempts, int) or \
                self.attempts < 1:
            raise ValueError(f"Retry: attempts must be a whole number >= 1, got "
                             f"{self.attempts!r}")

    def perform(self, ctx: RobotContext) -> Any:
        failures: list[tuple[str, PlanFailure]] = []
        with _node(ctx, "Retry"):
            for attempt in range(1, self.attempts + 1):
                try:
                    return _run(self.step, ctx)
                except MonitorFired:
                    raise
                except PlanFailure as failure:
                    failures.append((f"attempt {attempt}", failure))
                    if attempt == self.attempts:
                        break
                    if self.on_failure is not None:
                        self.on_failure(ctx, failure)
                    if ctx is not None:
                        ctx.observe()  # (the next try plans on what the world reports)
            raise _all_failed(failures)


def retry(step: Step, attempts: int = 2, on_failure: Recovery | None = None) -> Retry:
    """`Retry(step, attempts, on_failure)`."""
    return Retry(step, attempts, on_failure)


@dataclass
class Monitor:
    """Run a step while a condition is asked at every state of every motion; when it
    holds, the motion brakes to rest and `MonitorFired` escapes."""

    condition: Condition
    step: Step
    name: str = "monitor"

    def perform(self, ctx: RobotContext) -> Any:
        watch = Watch(self.condition, self.name)
        with _node(ctx, "Monitor"):
            ctx.monitors.append(watch)
            try:
                try:
                    result = _run(self.step, ctx)
                except PlanFailure:
                    if watch.fired is None:
                        raise
                    result = None
            finally:
                ctx.monitors.remove(watch)
            if watch.fired is not None:
                raise watch.fired
            return result
