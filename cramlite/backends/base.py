"""The seam between planning and execution: `ProcessModules` and `Backend`.

`ProcessModules` is what a simulator or a real robot's drivers implement: it receives
timed, collision-checked trajectories (planned on the planning scene by the motion
designators) and follows them, and it reports what the robot and its world are like
(joint states, the base pose, where the drawers and the items are: perception on a real
robot). Nothing else reaches the executing world: planning asks the scene only, and the
scene is updated from these reports.

A `Backend` is a process-modules implementation together with the world it loads from a
setup (a PyBullet world, a kinematic world state of its own, ...): it resets that world
to the setup's start between trials and closes it when done.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.scene.transforms import Pose
from cramlite.world.setup import Setup

BasePose = tuple[float, float, float]
#: A settling item is at rest below these speeds, seen so twice in a row, looking every
#: SETTLE_CHUNK_STEPS physics steps (the physics backends' `settle`).
REST_LINEAR_M_S = 0.005
REST_ANGULAR_RAD_S = 0.05
SETTLE_CHUNK_STEPS = 6
#: Called with the index of each state right after the robot reached it.
StateObserver = Callable[[int], None] | None


@dataclass
class PhysicsRecord:
    """What a physics backend measured since the trial started (`simulator_report`)."""

    steps: int = 0  #: physics steps taken
    deepest_contact_m: float = 0.0  #: the deepest item contact seen while settling

    def report(self) -> dict[str, float]:
        return {"physics_steps": self.steps,
                "deepest_contact_m": round(self.deepest_contact_m, 6)}


class ProcessModules(ABC):
    """Executes atomic motions and reports the world. Implement this to drive another
    simulator or a real robot."""

    # -- execution ----------------------------------------------------------------------
    @abstractmethod
    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        """Drive through the trajectory's poses (x, y, yaw) at its times."""

    @abstractmethod
    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        """Move the trajectory's joints (arm, torso, gripper) through its states; a
        trajectory with `world` values moves a drawer or door with the hand."""

    #: True where the states between a trajectory's first and last change nothing in the
    #: executing world while nothing watches them (`on_state` is None): a simulation that
    #: moves the robot kinematically goes straight to the last state then.
    skips_unwatched_states: ClassVar[bool] = False

    def execute_parallel(self, base: BaseTrajectory, joints: JointTrajectory,
                         on_state: StateObserver = None) -> None:
        """Drive and move joints at once: `base` and `joints` share their times (state i of
        one belongs with state i of the other; the planner checked them together). This
        default steps the two primitives state by state (or, where nothing watches and
        the states between change nothing, sends each whole: both end at their last
        state); a robot's driver should send both at once instead."""
        import numpy as np

        if on_state is None and self.skips_unwatched_states:
            self.execute_base_trajectory(base)
            self.execute_joint_trajectory(joints)
            return
        for i in range(len(base.times)):
            t = base.times[i:i + 1]
            self.execute_base_trajectory(BaseTrajectory(np.asarray(base.poses)[i:i + 1], t))
            self.execute_joint_trajectory(JointTrajectory(
                joints.names, np.asarray(joints.positions)[i:i + 1], t,
                {k: np.asarray(v)[i:i + 1] for k, v in joints.world.items()}))
            if on_state is not None:
                on_state(i)

    @abstractmethod
    def attach(self, arm: str, obj: str) -> None:
        """The gripper holds the object: it moves with the gripper from now on."""

    @abstractmethod
    def detach(self, arm: str, obj: str) -> None:
        """Let go of the object."""

    @abstractmethod
    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        """Let the world come to rest (a real robot just waits)."""

    # -- observation --------------------------------------------------------------------
    @abstractmethod
    def base_pose(self) -> BasePose: ...

    @abstractmethod
    def joint_positions(self, names: Sequence[str]) -> dict[str, float]: ...

    @abstractmethod
    def world_joint_positions(self) -> dict[str, float]:
        """Where the drawers and doors are (perception on a real robot)."""

    @abstractmethod
    def object_pose(self, obj: str) -> Pose:
        """Where an object's frame (the centre of its bottom face) is, as (position,
        quaternion x y z w)."""

    @abstractmethod
    def tool_pose(self, arm: str) -> Pose:
        """Where a gripper's tool frame is (forward kinematics of the measured joints)."""

    @abstractmethod
    def release_all(self) -> None:
        """Let go of everything (a new trial starts with empty hands)."""

    def simulator_report(self) -> dict[str, float]:
        """What a physics simulator measured since the trial started (none here): the
        physics steps it took and the deepest contact it saw while items settled (m)."""
        return {}


#: What a backend may be asked by the rest of cramlite: execution and observation. (A
#: test records every call a trial makes and finds nothing else.)
EXECUTION_CALLS = frozenset({"execute_base_trajectory", "execute_joint_trajectory",
                             "execute_parallel", "attach", "detach", "settle", "release_all"})
OBSERVATION_CALLS = frozenset({"base_pose", "joint_positions", "world_joint_positions",
                               "object_pose", "tool_pose", "simulator_report"})


class Backend(ABC):
    """A world that executes plans, loaded from a setup."""

    #: The name `--backend` knows it by.
    name: ClassVar[str] = ""
    #: Does the backend simulate physics (settling, pushing), or only kinematics?
    physics: ClassVar[bool] = False

    setup: Setup
    modules: ProcessModules

    @abstractmethod
    def reset(self, poses: dict[str, Pose] | None = None) -> None:
        """Back to the setup's start (the items at `poses` where given): empty hands,
        drawers and doors closed, the robot at its start with its joints at zero."""

    @abstractmethod
    def close(self) -> None: ...

    def __enter__(self) -> Backend:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
