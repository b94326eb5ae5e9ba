"""Grasps: where the gripper's tool frame goes relative to an object.

`front`: horizontal approach along the robot's heading, tool frame at the object's
middle height (capped). `top`: from above, tool x axis pointing down, at the object's
top. Flat objects (a spoon) only have `top`. Both are invariant to the object's yaw,
so a carried object can be put down facing any way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

GRASPS = ("front", "top")
FLAT_OBJECT_M = 0.04
FRONT_GRASP_MAX_HEIGHT_M = 0.12
#: Pre-grasp and retreat: back off along the approach (up, for a top grasp), and rise a
#: little too, so the gripper is clear of the surface and the neighbours on its way to
#: and from the carry or park pose.
PREGRASP_OFFSET_M = 0.10
PREGRASP_RISE_M = 0.04
RETREAT_RISE_M = 0.08
#: Lift after grasping, and height above the place pose from which an object is lowered.
LIFT_M = 0.08
#: Where a carried object is held while driving (robot frame): in front of the shoulder,
#: its bottom above every counter, upright as it was grasped (the tucked park pose would
#: tilt it and hang it into the furniture). A front grasp turns the tool toward the
#: robot's midline (pointing forward, the PR2's long gripper cannot hold it this close).
CARRY_X_M = 0.35
CARRY_Y_M = 0.20
CARRY_BOTTOM_Z_M = 1.03


def grasps_for(height_m: float) -> list[str]:
    return ["top"] if height_m < FLAT_OBJECT_M else ["front", "top"]


def grasp_height_m(grasp: str, object_height_m: float) -> float:
    """Height of the tool frame above the object's bottom."""
    if grasp == "front":
        return min(object_height_m / 2, FRONT_GRASP_MAX_HEIGHT_M)
    return object_height_m


def _rz(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


TOOL_DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # Ry(pi/2)


def tool_pose(grasp: str, bottom_centre: tuple[float, float, float], grasp_height: float,
              approach_yaw: float, offset_m: float = 0.0, rise_m: float = 0.0) -> pin.SE3:
    """Tool frame in the world for a grasp; `offset_m` backs off along the approach
    (front) or up (top) for pre-grasp and retreat poses, `rise_m` lifts a front one."""
    x, y, z = bottom_centre
    rotation = _rz(approach_yaw)
    position = np.array([x, y, z + grasp_height])
    if grasp == "front":
        position -= offset_m * rotation[:, 0]
        position[2] += rise_m
    else:
        rotation = rotation @ TOOL_DOWN
        position[2] += offset_m
    return pin.SE3(rotation, position)


def in_base_frame(world_pose: pin.SE3, base: tuple[float, float, float]) -> pin.SE3:
    x, y, yaw = base
    return pin.SE3(_rz(yaw), np.array([x, y, 0.0])).actInv(world_pose)


def raised(pose: pin.SE3, dz: float) -> pin.SE3:
    """The same tool pose `dz` metres higher (lifting, or hovering above a place pose)."""
    return pin.SE3(pose.rotation, pose.translation + np.array([0.0, 0.0, dz]))


def relative_pose(tool: pin.SE3, position: Sequence[float],
                  orientation: Sequence[float]) -> tuple[tuple[float, float, float],
                                                         tuple[float, float, float, float]]:
    """An object's pose (position, quaternion x, y, z, w) in the tool frame."""
    x, y, z, w = orientation
    obj = pin.SE3(pin.Quaternion(w, x, y, z).toRotationMatrix(), np.asarray(position, float))
    rel = tool.actInv(obj)
    q = pin.Quaternion(rel.rotation).coeffs()  # x, y, z, w
    return (tuple(map(float, rel.translation)), tuple(map(float, q)))


def carry_pose(grasp: str, grasp_height: float, arm: str) -> pin.SE3:
    """The tool pose (robot frame) that carries an object grasped with `grasp`."""
    side = -1.0 if arm == "right" else 1.0
    rotation = _rz(-side * math.pi / 2) if grasp == "front" else TOOL_DOWN
    return pin.SE3(rotation, np.array([CARRY_X_M, side * CARRY_Y_M,
                                       CARRY_BOTTOM_Z_M + grasp_height]))
