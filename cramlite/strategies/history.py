"""What was taken so far, for strategies whose choice depends on earlier steps.

A strategy with this mixin records its own choice as the step's taken item; a caller
that knows better (teacher-forced scoring, where the human took the observed item)
says so with `observe(taken)`, which replaces the recorded choice, or records the step
if the strategy was not asked (`tied` only). The robot's plans never call `observe`:
there the chosen item is the one taken.
"""

from __future__ import annotations

from cramlite.strategies.candidates import Candidate


class TakenHistory:
    """Mixin: `self.taken`, the items taken in this episode, oldest first."""

    #: `tied` is the exact set the strategy picks uniformly from at this step, given the
    #: history (so exact expected APE and the vectorised fit apply), like memoryless ones.
    exact_ties = True

    def reset_history(self) -> None:
        self.taken: list[Candidate] = []
        self._provisional = False

    def record_choice(self, chosen: Candidate) -> None:
        """The strategy's own choice: taken unless `observe` says otherwise."""
        self.taken.append(chosen)
        self._provisional = True

    def observe(self, taken: Candidate) -> None:
        """The item actually taken at the step just decided (or scored)."""
        if self._provisional:
            self.taken[-1] = taken
        else:
            self.taken.append(taken)
        self._provisional = False
