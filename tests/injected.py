"""Process modules with injected failures, for fall-through tests."""

from __future__ import annotations

from cramlite.designators import NavigationFailed, SimulatedProcessModules


class NavigationFailsOnce(SimulatedProcessModules):
    """Injected failure: the first drive is refused (say, a person steps in the way)."""

    def __init__(self, world):
        super().__init__(world)
        self.refused = 0

    def execute_base_trajectory(self, trajectory, on_state=None):
        if self.refused == 0:
            self.refused += 1
            raise NavigationFailed("path blocked by a person (injected)")
        super().execute_base_trajectory(trajectory, on_state)
