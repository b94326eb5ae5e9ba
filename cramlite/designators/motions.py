"""Motion designators: atomic movements, planned, checked, timed and then executed.

A motion never jumps to its goal: the base follows an OMPL path (states 2 cm apart,
checked against the 2D footprint map), the arm a joint-space path (the straight one if it
is free, else one OMPL plans around obstacles), and each becomes a timed trajectory that
the context's process modules execute state by state. No collision-free path raises
`MotionPlanningFailed`, so the action above can fall through to its next candidate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import MotionPlanningFailed, ObjectUnreachable
from cramlite.designators.grasps import in_base_frame
from cramlite.designators.tasks import recorded
from cramlite.motion.base_timing import time_base_path
from cramlite.motion.ik import arm_ik, arm_prefix
from cramlite.motion.trajectory import BaseTrajectory, time_joint_path
from cramlite.scene.models import pr2_model

BasePose = tuple[float, float, float]
#: The finger joint the others of a gripper follow (see the URDF's mimic tags).
GRIPPER_LEADER = "gripper_l_finger_joint"
GRIPPER_OPEN, GRIPPER_CLOSED = 0.5, 0.0


def move_joints(ctx: RobotContext, joints: dict[str, float], allow_contact: Sequence[str] = (),
                ) -> None:
    """Plan, time and execute a joint motion to `joints` (only the joints that change move);
    raises MotionPlanningFailed if no collision-free path is found."""
    names = list(joints)
    current = ctx.scene.joint_positions(names)
    start = np.array([current[n] for n in names])
    goal = ctx.limits.unwrap_goal(names, start, np.array([joints[n] for n in names]))
    moving = [i for i in range(len(names)) if abs(goal[i] - start[i]) > 1e-9]
    if not moving:
        return
    names = [names[i] for i in moving]
    start, goal = start[moving], goal[moving]
    check = ctx.collisions.check(names, ignore=allow_contact)
    path = ctx.arm_planner.plan(check, start, goal, ctx.rng)
    why = "" if path is not None else _why(check, start, goal, ctx)
    ctx.arm_motions += 1
    if path is None:
        raise MotionPlanningFailed(f"no collision-free path for {_joint_group(names)}{why}")
    ctx.planned_motions += path.planned
    ctx.move_joints(time_joint_path(names, path.vertices, ctx.limits))


def _joint_group(names: Sequence[str]) -> str:
    arms = sorted({"right" if n.startswith("r_") else "left" for n in names
                   if n[:2] in ("r_", "l_")})
    parts = [f"the {a} arm" for a in arms] + (["the torso"] if "torso_lift_joint" in names
                                                else [])
    return " and ".join(parts) or "the joints"


def _why(scene, start: np.ndarray, goal: np.ndarray, ctx: RobotContext) -> str:
    contacts = scene.contacts(goal)
    if contacts:
        return f": at the goal {contacts[0].describe()}"
    return (f" within {ctx.arm_planner.options.time_limit_s:.1f} s "
            "(the straight path collides and OMPL found no detour)")


@dataclass(frozen=True)
class MoveMotion:
    """Drive the base along a checked path (waypoints x, y, yaw)."""

    waypoints: Sequence[BasePose]

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        # (corners are blended where the footprint check, as the path's, says free)
        timed = time_base_path(self.waypoints, ctx.options.base_limits,
                               ctx.base_checker().is_free)
        ctx.drive(BaseTrajectory(timed.poses, timed.times))


@dataclass(frozen=True)
class MoveArmJointsMotion:
    """Move arm (and torso) joints to angles by name along a collision-free path."""

    joints: dict[str, float]
    #: Objects the motion may touch (the one being grasped or just put down).
    allow_contact: tuple[str, ...] = ()

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        move_joints(ctx, self.joints, self.allow_contact)


@dataclass(frozen=True)
class MoveTCPMotion:
    """Move an arm's tool frame to a pose in the world (x, y, z, rotation) via IK."""

    arm: str
    pose: pin.SE3  #: target of the tool frame, world coordinates

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        ik = arm_ik(self.arm)
        target = in_base_frame(self.pose, ctx.scene.base)
        seed = ctx.scene.joint_positions(ik.joint_names)
        solution = (ik.solve(target, ctx.rng, seed, fixed_torso_m=seed["torso_lift_joint"])
                    or ik.solve(target, ctx.rng, seed))
        if solution is None:
            x, y, z = self.pose.translation
            raise ObjectUnreachable(f"no IK solution for the {self.arm} tool frame at "
                                    f"({x:.2f}, {y:.2f}, {z:.2f}) from here")
        move_joints(ctx, solution.joints)


@dataclass(frozen=True)
class MoveTorsoMotion:
    height_m: float

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        move_joints(ctx, {"torso_lift_joint": self.height_m})


def gripper_joints(arm: str, state: str) -> dict[str, float]:
    """The finger joints of a gripper open or closed: its leading joint and the five that
    follow it (the URDF's mimic tags)."""
    value = GRIPPER_OPEN if state == "open" else GRIPPER_CLOSED
    return pr2_model().with_mimics({f"{arm_prefix(arm)}_{GRIPPER_LEADER}": value})


@dataclass(frozen=True)
class MoveGripperMotion:
    """Open or close one gripper (its fingers follow a checked trajectory too)."""

    arm: str
    state: str  # "open" | "close"
    allow_contact: tuple[str, ...] = ()

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        if self.state not in ("open", "close"):
            raise ValueError(f"gripper state must be 'open' or 'close', got {self.state!r}")
        move_joints(ctx, gripper_joints(self.arm, self.state), self.allow_contact)


@dataclass(frozen=True)
class AttachMotion:
    """The object moves with the gripper from now on."""

    arm: str
    obj: str

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.attach(self.arm, self.obj)
        ctx.observe()
        ctx.scene.attach(self.arm, self.obj)
        ctx.footprint_stale = True


@dataclass(frozen=True)
class DetachMotion:
    arm: str
    obj: str

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.detach(self.arm, self.obj)
        ctx.scene.detach(self.obj)
        ctx.observe()
        ctx.footprint_stale = True
