"""The head: `LookAtAction` points the PR2's head at a point (pan and tilt along a checked,
timed trajectory, as every other joint motion).

The gaze is the x axis of `high_def_frame`, the head's high-resolution camera (the
narrow-stereo and Kinect frames sit beside it on the same plate). Pan turns about the
vertical, tilt about the pan link's y axis (positive: looking down), so a few steps of
"turn the gaze onto the point from where it is" converge to within micro-radians (two for
a glance, more for a half turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import MotionPlanningFailed, ObjectNotFound, finite_numbers
from cramlite.designators.motions import move_joints
from cramlite.designators.tasks import ActionDesignator

PAN, TILT = "head_pan_joint", "head_tilt_joint"
GAZE_FRAME = "high_def_frame"
#: How far from the point the gaze may end (degrees).
LOOK_TOLERANCE_DEG = 2.0


def gaze_error_deg(ctx: RobotContext, point: tuple[float, float, float],
                   joints: dict[str, float] | None = None) -> float:
    """The angle between the camera's gaze and the direction to `point` (degrees)."""
    frame = ctx.scene.link_matrix(GAZE_FRAME, joints)
    to_point = np.asarray(point, dtype=float) - frame[:3, 3]
    cos = float(frame[:3, 0] @ to_point / max(np.linalg.norm(to_point), 1e-12))
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


def look_at_joints(ctx: RobotContext, point: tuple[float, float, float]) -> dict[str, float]:
    """Head pan and tilt that point the gaze at `point` (within the joints' limits; a
    MotionPlanningFailed if the point is out of the head's reach, e.g. below its chin)."""
    joints = ctx.scene.joint_positions([PAN, TILT])
    start_pan = joints[PAN]
    for _ in range(12):  # (a half turn takes more steps than a glance: the camera sits
        frame = ctx.scene.link_matrix(GAZE_FRAME, joints)  # off the pan axis)
        local = frame[:3, :3].T @ (np.asarray(point, dtype=float) - frame[:3, 3])
        step = (math.atan2(local[1], local[0]),
                math.atan2(-local[2], math.hypot(local[0], local[1])))
        joints = {PAN: joints[PAN] + step[0], TILT: joints[TILT] + step[1]}
        if max(abs(step[0]), abs(step[1])) < 1e-7:
            break
    limits = ctx.scene.robot.joints
    joints[PAN] = _wrapped_into(joints[PAN], limits[PAN].lower, limits[PAN].upper,
                                near=start_pan)
    for name, value in joints.items():
        if not limits[name].lower - 1e-9 <= value <= limits[name].upper + 1e-9:
            raise MotionPlanningFailed(
                f"the head cannot look at ({point[0]:.2f}, {point[1]:.2f}, {point[2]:.2f}): "
                f"{name} would be {value:.2f} rad, beyond [{limits[name].lower:.2f}, "
                f"{limits[name].upper:.2f}]")
    return joints


def _wrapped_into(angle: float, lower: float, upper: float, near: float) -> float:
    """The angle equivalent to `angle` (a multiple of 2 pi away) within [lower, upper]
    that is nearest `near`, or `angle` itself if none is (the caller reports it): the
    pan's correction accumulates, so a gaze behind the head can come out a turn away."""
    candidates = [angle + 2 * math.pi * turns for turns in range(-2, 3)]
    within = [a for a in candidates if lower - 1e-9 <= a <= upper + 1e-9]
    return min(within, key=lambda a: abs(a - near)) if within else angle


@dataclass
class LookAtAction(ActionDesignator):
    """Point the head's camera at a point in the world (or at an object, by name: its
    middle as the scene believes it)."""

    target: tuple[float, float, float] | str

    def __post_init__(self) -> None:  # (a point that is no point: refused where written)
        if not isinstance(self.target, str):
            finite_numbers(self.target, 3, "LookAtAction: target")

    def _point(self, ctx: RobotContext) -> tuple[float, float, float]:
        if isinstance(self.target, str):
            if self.target not in ctx.scene.items:
                raise ObjectNotFound(f"no such object; expected one of "
                                     f"{', '.join(ctx.scene.items)} or a point (x, y, z)",
                                     obj=self.target)
            (x, y, z), _ = ctx.scene.object_pose(self.target)
            return (x, y, z + ctx.scene.items[self.target].height() / 2)
        return tuple(float(v) for v in self.target)

    def execute(self, ctx: RobotContext) -> tuple[float, float, float]:
        point = self._point(ctx)
        move_joints(ctx, look_at_joints(ctx, point))
        return point

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        point = result if result is not None else self._point(ctx)
        error = gaze_error_deg(ctx, point)  # (with the head as the modules report it)
        if error > LOOK_TOLERANCE_DEG:
            raise MotionPlanningFailed(f"the head looks {error:.1f} deg away from the point")
