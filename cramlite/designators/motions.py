"""Motion designators: atomic movements, executed by the context's process modules."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cramlite.designators.context import RobotContext
from cramlite.motion.base_planner import path_length_m

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
