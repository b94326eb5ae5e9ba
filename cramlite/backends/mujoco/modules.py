"""The MuJoCo backend's process modules: kinematic execution, physics for released items.

The robot and a gripped handle follow every state of a planned trajectory (set
kinematically, as the pybullet backend does: the trajectories were planned and checked on
the planning scene). A held item is carried rigidly with its gripper: its free joint is
set from the tool frame at every state (a weld of infinite stiffness; the fingers, which
stop at the item's width, are not what holds it). Released items are stepped by MuJoCo's
physics until they rest (`settle`), and wherever physics leaves them (settled, pushed) is
what `object_pose` reports back to the planning scene.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cramlite.backends.base import (
    REST_ANGULAR_RAD_S,
    REST_LINEAR_M_S,
    SETTLE_CHUNK_STEPS,
    BasePose,
    PhysicsRecord,
    ProcessModules,
    StateObserver,
)
from cramlite.backends.mujoco.world import TIME_STEP_S, MujocoWorld
from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.scene.scene import tool_frame
from cramlite.scene.transforms import Pose, inverse, matrix_pose, pose_matrix


class MujocoModules(ProcessModules):
    """Kinematic execution in a `MujocoWorld`, state by state; physics when settling."""

    def __init__(self, world: MujocoWorld):
        self.world = world
        #: Held items: the item's pose in the tool frame, by item (and its arm).
        self._attached: dict[str, tuple[str, np.ndarray]] = {}
        self.physics = PhysicsRecord()

    def release_all(self) -> None:
        for obj, (arm, _) in list(self._attached.items()):
            self.detach(arm, obj)

    skips_unwatched_states = True

    def _states(self, count: int, on_state: StateObserver) -> range:
        """Every state while something watches (a trace), else the last (nothing in this
        world acts on the states between: physics runs only when settling)."""
        return range(count) if on_state is not None else range(count - 1, count)

    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        for i in self._states(len(trajectory.poses), on_state):
            x, y, yaw = trajectory.poses[i]
            self.world.set_base_pose(float(x), float(y), float(yaw))
            self._carry()
            if on_state is not None:
                on_state(i)

    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        held = set(self._attached)
        for i in self._states(len(trajectory.positions), on_state):
            self.world.set_joint_positions(
                {n: float(v) for n, v in zip(trajectory.names, trajectory.positions[i],
                                             strict=True)})
            for joint, values in trajectory.world.items():  # the handle pulls the drawer
                self.world.forward()
                self.world.set_world_joint(joint, float(values[i]), exclude=held)
            self._carry()
            if on_state is not None:
                on_state(i)

    def attach(self, arm: str, obj: str) -> None:
        self.world.forward()
        tool = pose_matrix(*self.world.link_pose(tool_frame(arm)))
        item = pose_matrix(*self.world.object_pose(obj))
        self._attached[obj] = (arm, inverse(tool) @ item)

    def detach(self, arm: str, obj: str) -> None:
        self._carry()
        self._attached.pop(obj)

    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        """Step physics until `objects` rest (or `seconds` have passed); the robot, the
        drawers and doors and held items are put back where they were (physics does not
        move what the robot moves)."""
        w = self.world
        robot = w.joint_positions()
        drawers = w.world_joint_positions()
        held = {obj: w.object_pose(obj) for obj in self._attached}
        steps = max(1, round(seconds / TIME_STEP_S))
        done = resting = 0
        w.data.qvel[:] = 0.0
        while done < steps:
            chunk = min(SETTLE_CHUNK_STEPS, steps - done)
            w.step(chunk)
            done += chunk
            self.physics.deepest_contact_m = max([self.physics.deepest_contact_m,
                                                  *(depth for *_, depth in w.contacts())])
            for obj, pose in held.items():
                w.set_object_pose(obj, *pose)
            resting = resting + 1 if objects and all(
                linear < REST_LINEAR_M_S and angular < REST_ANGULAR_RAD_S
                for linear, angular in map(w.object_speed, objects)) else 0
            if resting >= 2:  # at rest over two looks, not at the top of a bounce
                break
        self.physics.steps += done
        w.set_joint_positions(robot)
        for name, value in drawers.items():
            w.data.qpos[w.world_qpos[name]] = value
        w.data.qvel[:] = 0.0
        w.forward()
        self._carry()

    def simulator_report(self) -> dict[str, float]:
        return self.physics.report()

    def base_pose(self) -> BasePose:
        return self.world.base_pose()

    def joint_positions(self, names: Sequence[str]) -> dict[str, float]:
        return self.world.joint_positions(list(names))

    def world_joint_positions(self) -> dict[str, float]:
        return self.world.world_joint_positions()

    def object_pose(self, obj: str) -> Pose:
        """Where an item is, to the micrometre (as the pybullet backend reports it)."""
        (x, y, z), orientation = self.world.object_pose(obj)
        return (round(x, 6), round(y, 6), round(z, 6)), orientation

    def tool_pose(self, arm: str) -> Pose:
        self.world.forward()
        return self.world.link_pose(tool_frame(arm))

    def _carry(self) -> None:
        if not self._attached:
            return
        self.world.forward()
        for obj, (arm, relative) in self._attached.items():
            tool = pose_matrix(*self.world.link_pose(tool_frame(arm)))
            self.world.set_object_pose(obj, *matrix_pose(tool @ relative))
