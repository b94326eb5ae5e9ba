"""Headless images of a world with PyBullet's TinyRenderer (no display needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cramlite.world.bullet import p
from cramlite.world.world import World


def render(world: World, width: int = 1024, height: int = 768,
           target: tuple[float, float, float] = (0.3, 0.2, 0.5), distance: float = 5.6,
           yaw_deg: float = 135.0, pitch_deg: float = -48.0, shadow: bool = True) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) seen from an orbiting camera."""
    view = p.computeViewMatrixFromYawPitchRoll(target, distance, yaw_deg, pitch_deg, 0, 2)
    proj = p.computeProjectionMatrixFOV(50, width / height, 0.05, 30.0)
    _, _, rgba, _, _ = p.getCameraImage(width, height, view, proj,
                                        renderer=p.ER_TINY_RENDERER,
                                        lightDirection=(-0.4, 0.6, 1.0), shadow=int(shadow),
                                        physicsClientId=world.client)
    image = np.reshape(np.asarray(rgba, dtype=np.uint8), (height, width, 4))
    return image[:, :, :3]


def save_png(image: np.ndarray, path: str | Path) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)
    return path
