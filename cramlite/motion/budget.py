"""A planner's budget counted in work done, not seconds.

OMPL's `solve(seconds)` stops on the host's clock: on a loaded machine the same query with
the same seed finds a path on one run and fails on the next (a CI run failed that way), so
a trial's seed alone would not decide its result. Counting the work the planner's
state-validity checks do instead makes a query's outcome a function of its seed; a slower
machine only takes longer.
"""

from __future__ import annotations

from collections.abc import Callable

from ompl import base as ob

#: The search also ends once its termination condition has been asked this many times in
#: a row with no work done in between (about a second of OMPL waiting for a valid goal,
#: which asks about twice every 10 ms for as long as the condition allows: a goal that is
#: not free would hold the search there for ever). Safe for a planner that asks once a
#: step, on the thread that searches, and checks a state at least in every step (OMPL's
#: RRTConnect); not for one that asks from another thread while it works (the PRMs).
IDLE_ASKS = 200


class CheckBudget:
    """Wraps a validity function and counts its work: one unit a state checked, plus
    what `extra()` adds (e.g. the exact pair tests those checks made, which cost about as
    much as a state's broadphase each). `condition()` ends the planner's search once
    `max_work` units are spent, or once it is asked `idle_asks` times in a row with
    nothing done in between (None: never; see `IDLE_ASKS`)."""

    def __init__(self, valid: Callable[..., bool], max_work: int,
                 extra: Callable[[], int] | None = None, idle_asks: int | None = None):
        self._valid = valid
        self.max_work = max_work
        self.max_idle_asks = idle_asks
        self.states = 0
        self._extra = extra
        self._extra_start = extra() if extra is not None else 0
        self._asked_at = -1  # (the work done when the condition was last asked)
        self.idle_asks = 0

    def __call__(self, state) -> bool:
        self.states += 1
        return self._valid(state)

    @property
    def used(self) -> int:
        """Work spent so far."""
        extra = self._extra() - self._extra_start if self._extra is not None else 0
        return self.states + extra

    def exhausted(self) -> bool:
        used = self.used
        if used == self._asked_at:
            self.idle_asks += 1
        else:
            self._asked_at, self.idle_asks = used, 0
        return used >= self.max_work or (self.max_idle_asks is not None and
                                          self.idle_asks >= self.max_idle_asks)

    def condition(self) -> ob.PlannerTerminationCondition:
        """Terminate when the budget is spent (the planner also stops at a solution)."""
        return ob.PlannerTerminationCondition(self.exhausted)
