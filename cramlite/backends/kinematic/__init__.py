"""The kinematic backend: no physics engine, a world state of its own.

The state is kept in a `PlanningScene` object of the backend's own (the same models as
the planner's, a separate belief: the planner's scene changes only from what these
process modules report). Trajectories step it; an attached item moves with its gripper;
a drawer carries what is inside it; a released item rests where it was placed (its
placement was checked by the planner: nothing here lets it fall). It runs wherever
Pinocchio does (every Python cramlite supports), it is the fastest way to benchmark
strategies, and it is a test double for the designators.
"""

from __future__ import annotations

from collections.abc import Sequence

from cramlite.backends.base import Backend, BasePose, ProcessModules, StateObserver
from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.scene.scene import PlanningScene, tool_frame
from cramlite.scene.transforms import Pose, matrix_pose
from cramlite.world.setup import Setup


class KinematicModules(ProcessModules):
    """Process modules that move a kinematic world state through every trajectory."""

    def __init__(self, state: PlanningScene):
        self.state = state

    def release_all(self) -> None:
        for item in list(self.state.held):
            self._let_go(item)

    skips_unwatched_states = True

    def _states(self, count: int, on_state: StateObserver) -> range:
        """Every state while something watches; else the last one (nothing in a
        kinematic world acts on the states between)."""
        return range(count) if on_state is not None else range(count - 1, count)

    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        for i in self._states(len(trajectory.poses), on_state):
            self.state.belief.base = tuple(float(v) for v in trajectory.poses[i])
            if on_state is not None:
                on_state(i)

    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        joints = self.state.belief.joints
        for i in self._states(len(trajectory.positions), on_state):
            for name, value in zip(trajectory.names, trajectory.positions[i], strict=True):
                joints[name] = float(value)
            for joint, values in trajectory.world.items():  # the handle pulls the drawer
                self.state.set_world_joint(joint, float(values[i]), carry=True)
            if on_state is not None:
                on_state(i)

    def attach(self, arm: str, obj: str) -> None:
        self.state.attach(arm, obj)

    def detach(self, arm: str, obj: str) -> None:
        self._let_go(obj)

    def _let_go(self, obj: str) -> None:
        """The item stays where the gripper let go of it."""
        self.state.belief.poses[obj] = matrix_pose(self.state.item_matrix(obj))
        self.state.detach(obj)

    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        """Nothing moves by itself in a kinematic world."""

    def base_pose(self) -> BasePose:
        return self.state.base

    def joint_positions(self, names: Sequence[str]) -> dict[str, float]:
        return self.state.joint_positions(names)

    def world_joint_positions(self) -> dict[str, float]:
        return self.state.world_joint_positions()

    def object_pose(self, obj: str) -> Pose:
        if obj in self.state.held:
            return matrix_pose(self.state.item_matrix(obj))
        return self.state.object_pose(obj)

    def tool_pose(self, arm: str) -> Pose:
        return matrix_pose(self.state.link_matrix(tool_frame(arm)))


class KinematicBackend(Backend):
    """A kinematic world of the setup (see the module's doc)."""

    name = "kinematic"
    physics = False

    def __init__(self, setup: Setup):
        self.setup = setup
        self.state = PlanningScene(setup)
        self.modules = KinematicModules(self.state)

    def reset(self, poses: dict[str, Pose] | None = None) -> None:
        self.state.reset()
        for name, pose in (poses or {}).items():
            self.state.belief.poses[name] = pose

    def close(self) -> None:
        """(Nothing to let go of.)"""


__all__ = ["KinematicBackend", "KinematicModules"]
