"""Motion designators: atomic movements, executed by the context's process modules."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pinocchio as pin

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import ObjectUnreachable
from cramlite.designators.grasps import in_base_frame
from cramlite.motion.base_planner import path_length_m
from cramlite.motion.ik import arm_ik

BasePose = tuple[float, float, float]


@dataclass(frozen=True)
class MoveMotion:
    """Drive the base along a path (waypoints x, y, yaw)."""

    waypoints: Sequence[BasePose]

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.move_base(self.waypoints)
        ctx.base_path_m += path_length_m(self.waypoints)


@dataclass(frozen=True)
class MoveArmJointsMotion:
    """Move arm (and torso) joints to angles by name."""

    joints: dict[str, float]

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.move_joints(dict(self.joints))


@dataclass(frozen=True)
class MoveTCPMotion:
    """Move an arm's tool frame to a pose in the world (x, y, z, rotation) via IK."""

    arm: str
    pose: pin.SE3  #: target of the tool frame, world coordinates

    def perform(self, ctx: RobotContext) -> None:
        ik = arm_ik(self.arm)
        target = in_base_frame(self.pose, ctx.modules.base_pose())
        seed = ctx.modules.joint_positions(ik.joint_names)
        solution = ik.solve(target, ctx.rng, seed)
        if solution is None:
            x, y, z = self.pose.translation
            raise ObjectUnreachable(f"no IK solution for the {self.arm} tool frame at "
                                    f"({x:.2f}, {y:.2f}, {z:.2f}) from here")
        MoveArmJointsMotion(solution.joints).perform(ctx)


@dataclass(frozen=True)
class MoveTorsoMotion:
    height_m: float

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.move_joints({"torso_lift_joint": self.height_m})


@dataclass(frozen=True)
class MoveGripperMotion:
    """Open or close one gripper."""

    arm: str
    state: str  # "open" | "close"

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.move_gripper(self.arm, self.state)


@dataclass(frozen=True)
class AttachMotion:
    """The object moves with the gripper from now on."""

    arm: str
    obj: str

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.attach(self.arm, self.obj)


@dataclass(frozen=True)
class DetachMotion:
    arm: str
    obj: str

    def perform(self, ctx: RobotContext) -> None:
        ctx.modules.detach(self.arm, self.obj)
