"""Process modules with injected failures, for fall-through tests."""

from __future__ import annotations

from cramlite.backends.pybullet.modules import SimulatedProcessModules
from cramlite.designators import NavigationFailed
from cramlite.designators.failures import ContainerManipulationFailed


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


class HandlesNeedBothHandsFree(SimulatedProcessModules):
    """Injected failure: a drawer or door does not move while a hand holds something (say,
    its handle is too stiff to pull with one arm while the other carries an item)."""

    def __init__(self, world):
        super().__init__(world)
        self.refused = 0

    def execute_joint_trajectory(self, trajectory, on_state=None):
        if trajectory.world and self._attached:  # the arm follows a handle, a hand is full
            self.refused += 1
            raise ContainerManipulationFailed("the handle does not move (injected)")
        super().execute_joint_trajectory(trajectory, on_state)
