"""Rigid transforms as 4 x 4 numpy matrices, and poses as (position, quaternion x y z w).

The quaternion order x, y, z, w is the one traces and process modules speak (PyBullet's
and MuJoCo's users know it); everything the scene computes with is a matrix.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
Pose = tuple[Vec3, Quat]


def yaw_quat(yaw: float) -> Quat:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def quat_yaw(q: Sequence[float]) -> float:
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def quat_matrix(q: Sequence[float]) -> np.ndarray:
    """The rotation matrix of a quaternion (x, y, z, w; normalised here)."""
    x, y, z, w = (float(v) for v in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n == 0:
        raise ValueError("a zero quaternion is no rotation")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_quat(rotation: np.ndarray) -> Quat:
    """The quaternion (x, y, z, w, w >= 0) of a rotation matrix."""
    m = np.asarray(rotation, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        w, x = 0.25 * s, (m[2, 1] - m[1, 2]) / s
        y, z = (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        w, x = (m[2, 1] - m[1, 2]) / s, 0.25 * s
        y, z = (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        w, x = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s
        y, z = 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        w, x = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s
        y, z = (m[1, 2] + m[2, 1]) / s, 0.25 * s
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    return (float(x), float(y), float(z), float(w))


def pose_matrix(position: Sequence[float], quaternion: Sequence[float]) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = quat_matrix(quaternion)
    out[:3, 3] = position
    return out


def matrix_pose(matrix: np.ndarray) -> Pose:
    return (tuple(float(v) for v in matrix[:3, 3]), matrix_quat(matrix[:3, :3]))


def planar(x: float, y: float, yaw: float) -> np.ndarray:
    """The base's frame: at (x, y) on the floor, turned by yaw."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0],
                     [0.0, 0.0, 0.0, 1.0]])


def planar_many(poses: np.ndarray) -> np.ndarray:
    """`planar` of each row (x, y, yaw) of `poses` (N x 4 x 4; the same numbers: the
    sines and cosines are math's)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    yaws = poses[:, 2].tolist()
    c = np.array([math.cos(a) for a in yaws])
    s = np.array([math.sin(a) for a in yaws])
    out = np.zeros((len(poses), 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = c, -s, s, c
    out[:, 0, 3], out[:, 1, 3] = poses[:, 0], poses[:, 1]
    out[:, 2, 2] = out[:, 3, 3] = 1.0
    return out


def inverse(matrix: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    rotation = matrix[:3, :3].T
    out[:3, :3] = rotation
    out[:3, 3] = -rotation @ matrix[:3, 3]
    return out


def tilt_deg(quaternion: Sequence[float]) -> float:
    """How far an item's up axis is turned from the world's (degrees)."""
    up = quat_matrix(quaternion)[2, 2]
    return math.degrees(math.acos(max(-1.0, min(1.0, up))))
