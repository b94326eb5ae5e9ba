"""An orbiting camera: view and projection matrices, and points projected to pixels.

The camera is given as PyBullet's debug camera is (a target, a distance, yaw and pitch in
degrees, the z axis up, a 50 degree vertical field of view), so one camera description
serves every renderer cramlite has; a test checks these matrices are PyBullet's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.render.camera_modes import CAMERA_MODES

FIELD_OF_VIEW_DEG = 50.0
NEAR_M, FAR_M = 0.05, 30.0


@dataclass(frozen=True)
class Camera:
    target: tuple[float, float, float]
    distance: float
    yaw_deg: float
    pitch_deg: float

    @property
    def eye(self) -> np.ndarray:
        yaw, pitch = math.radians(self.yaw_deg), math.radians(self.pitch_deg)
        back = np.array([math.cos(pitch) * math.sin(yaw), -math.cos(pitch) * math.cos(yaw),
                         -math.sin(pitch)])
        return np.asarray(self.target, dtype=float) + self.distance * back

    def view(self) -> np.ndarray:
        """World to camera (4 x 4; the camera looks along its -z, y up)."""
        eye, target = self.eye, np.asarray(self.target, dtype=float)
        back = (eye - target) / np.linalg.norm(eye - target)
        right = np.cross([0.0, 0.0, 1.0], back)
        if np.linalg.norm(right) < 1e-9:  # (looking straight down)
            right = np.array([1.0, 0.0, 0.0])
        right /= np.linalg.norm(right)
        up = np.cross(back, right)
        out = np.eye(4)
        out[0, :3], out[1, :3], out[2, :3] = right, up, back
        out[:3, 3] = -out[:3, :3] @ eye
        return out

    def projection(self, width: int, height: int) -> np.ndarray:
        """Camera to clip space (OpenGL's perspective, vertical field of view)."""
        f = 1.0 / math.tan(math.radians(FIELD_OF_VIEW_DEG) / 2)
        aspect = width / height
        out = np.zeros((4, 4))
        out[0, 0], out[1, 1] = f / aspect, f
        out[2, 2] = (FAR_M + NEAR_M) / (NEAR_M - FAR_M)
        out[2, 3] = 2 * FAR_M * NEAR_M / (NEAR_M - FAR_M)
        out[3, 2] = -1.0
        return out

    def project(self, points: np.ndarray, width: int, height: int) -> np.ndarray:
        """Pixel coordinates (n x 2) of world points (n x 3)."""
        return self.pixels(points, width, height)[:, :2]

    def pixels(self, points: np.ndarray, width: int, height: int) -> np.ndarray:
        """(u, v, depth along the view) of world points (n x 3); depth <= 0: behind."""
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        camera = pts @ self.view()[:3, :3].T + self.view()[:3, 3]
        clip = np.c_[camera, np.ones(len(camera))] @ self.projection(width, height).T
        w = np.where(np.abs(clip[:, 3]) < 1e-12, 1e-12, clip[:, 3])
        ndc = clip[:, :3] / w[:, None]
        return np.c_[(ndc[:, 0] + 1) / 2 * width, (1 - ndc[:, 1]) / 2 * height, -camera[:, 2]]


def camera(spec: dict | Camera | None, default: dict) -> Camera:
    if isinstance(spec, Camera):
        return spec
    values = {**default, **(spec or {})}
    return Camera(tuple(values["target"]), float(values["distance"]), float(values["yaw_deg"]),
                  float(values["pitch_deg"]))


#: The default camera of `cramlite show`; the replay camera (from above the south end, the
#: island on the left, the counter on the right, the robot between them).
SHOW_CAMERA = {"target": (0.3, 0.2, 0.5), "distance": 5.6, "yaw_deg": 135.0,
               "pitch_deg": -48.0}
REPLAY_CAMERA = {"target": (0.15, 0.15, 0.3), "distance": 5.6, "yaw_deg": -20.0,
                 "pitch_deg": -52.0}


#: How a replay's camera moves: `fixed` (REPLAY_CAMERA), `top` (straight down on the
#: whole kitchen) or `follow` (behind and above the robot, looking where it faces: into
#: the drawer it opens, onto the spot it places on).
TOP_CAMERA = {"target": (0.15, 0.15, 0.0), "distance": 8.6, "yaw_deg": 0.0,
              "pitch_deg": -89.0}
FOLLOW_DISTANCE_M, FOLLOW_PITCH_DEG, FOLLOW_HEIGHT_M = 2.6, -42.0, 0.75


def replay_view(mode: str, base: Sequence[float]) -> dict:
    """The camera of a replay frame whose robot base is at `base` (x, y, yaw)."""
    if mode == "fixed":
        return dict(REPLAY_CAMERA)
    if mode == "top":
        return dict(TOP_CAMERA)
    if mode == "follow":
        x, y, yaw = (float(v) for v in base[:3])
        ahead = 0.6  # (look a little in front of the robot: where its hands work)
        return {"target": (x + ahead * math.cos(yaw), y + ahead * math.sin(yaw),
                           FOLLOW_HEIGHT_M),
                "distance": FOLLOW_DISTANCE_M, "yaw_deg": math.degrees(yaw) - 90.0,
                "pitch_deg": FOLLOW_PITCH_DEG}
    raise ValueError(f"camera {mode!r}: expected one of {', '.join(CAMERA_MODES)}")


def as_tuple(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in values)
