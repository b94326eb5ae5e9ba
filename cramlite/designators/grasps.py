"""Grasps: where the gripper's tool frame goes relative to an object.

`front`: horizontal approach along the robot's heading, tool frame at the object's
middle height (capped). `top`: from above, tool x axis pointing down, at the object's
top. Flat objects (a spoon) only have `top`. Both are invariant to the object's yaw,
so a carried object can be put down facing any way.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

GRASPS = ("front", "top")
FLAT_OBJECT_M = 0.04
FRONT_GRASP_MAX_HEIGHT_M = 0.12
PREGRASP_OFFSET_M = 0.10
LIFT_M = 0.08


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
              approach_yaw: float, offset_m: float = 0.0) -> pin.SE3:
    """Tool frame in the world for a grasp; `offset_m` backs off along the approach
    (front) or up (top) for pre-grasp and retreat poses."""
    x, y, z = bottom_centre
    rotation = _rz(approach_yaw)
    position = np.array([x, y, z + grasp_height])
    if grasp == "front":
        position -= offset_m * rotation[:, 0]
    else:
        rotation = rotation @ TOOL_DOWN
        position[2] += offset_m
    return pin.SE3(rotation, position)


def in_base_frame(world_pose: pin.SE3, base: tuple[float, float, float]) -> pin.SE3:
    x, y, yaw = base
    return pin.SE3(_rz(yaw), np.array([x, y, 0.0])).actInv(world_pose)
