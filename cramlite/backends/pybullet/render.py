"""Headless images of a world with PyBullet's TinyRenderer (no display needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import World

#: The default camera of `render` (and `cramlite show`).
DEFAULT_CAMERA = {"target": (0.3, 0.2, 0.5), "distance": 5.6, "yaw_deg": 135.0,
                  "pitch_deg": -48.0}
FIELD_OF_VIEW_DEG = 50


def _matrices(width: int, height: int, target, distance: float, yaw_deg: float,
              pitch_deg: float) -> tuple[list[float], list[float]]:
    view = p.computeViewMatrixFromYawPitchRoll(target, distance, yaw_deg, pitch_deg, 0, 2)
    proj = p.computeProjectionMatrixFOV(FIELD_OF_VIEW_DEG, width / height, 0.05, 30.0)
    return list(view), list(proj)


def render(world: World, width: int = 1024, height: int = 768,
           target: tuple[float, float, float] = DEFAULT_CAMERA["target"],
           distance: float = DEFAULT_CAMERA["distance"],
           yaw_deg: float = DEFAULT_CAMERA["yaw_deg"],
           pitch_deg: float = DEFAULT_CAMERA["pitch_deg"], shadow: bool = True) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) seen from an orbiting camera."""
    view, proj = _matrices(width, height, target, distance, yaw_deg, pitch_deg)
    _, _, rgba, _, _ = p.getCameraImage(width, height, view, proj,
                                        renderer=p.ER_TINY_RENDERER,
                                        lightDirection=(-0.4, 0.6, 1.0), shadow=int(shadow),
                                        physicsClientId=world.client)
    image = np.reshape(np.asarray(rgba, dtype=np.uint8), (height, width, 4))
    return image[:, :, :3]


def project(points: np.ndarray, width: int, height: int, **camera) -> np.ndarray:
    """Pixel coordinates (n x 2) of world points (n x 3) in an image of `render` with the
    same camera (the default one unless given)."""
    cam = {**DEFAULT_CAMERA, **camera}
    view, proj = _matrices(width, height, cam["target"], cam["distance"], cam["yaw_deg"],
                           cam["pitch_deg"])
    matrix = np.array(proj).reshape(4, 4).T @ np.array(view).reshape(4, 4).T
    homogeneous = np.c_[np.atleast_2d(points), np.ones(len(np.atleast_2d(points)))]
    clip = homogeneous @ matrix.T
    ndc = clip[:, :3] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * width, (1 - ndc[:, 1]) / 2 * height]


def render_labelled(world: World, width: int = 1024, height: int = 768) -> np.ndarray:
    """`render` with every item labelled, each target marked (a square outline on its
    surface) and labelled, and the robot's start marked."""
    from cramlite.render.labels import label_setup

    image = render(world, width, height)
    if world.setup is None:
        return image
    positions = {name: obj.pose()[0] for name, obj in world.objects.items()}
    return label_setup(image, world.setup, positions,
                       lambda points: project(points, width, height))


def save_png(image: np.ndarray, path: str | Path) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)
    return path
