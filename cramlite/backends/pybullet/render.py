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
    from PIL import Image, ImageDraw

    image = Image.fromarray(render(world, width, height))
    setup = world.setup
    if setup is None:
        return np.asarray(image)
    draw = ImageDraw.Draw(image)
    half = 0.05  # target square half side (m)
    taken: list[tuple[float, float, float, float]] = []
    for spec in setup.items:
        t = spec.target
        corners = np.array([[t.x - half, t.y - half, t.z], [t.x + half, t.y - half, t.z],
                            [t.x + half, t.y + half, t.z], [t.x - half, t.y + half, t.z]])
        square = [tuple(c) for c in project(corners, width, height)]
        draw.polygon(square, outline=(200, 30, 30), width=2)
    start = setup.robot_start
    ring = np.array([[start.x + 0.45 * np.cos(a), start.y + 0.45 * np.sin(a), 0.01]
                     for a in np.linspace(0, 2 * np.pi, 33)])
    draw.line([tuple(c) for c in project(ring, width, height)], fill=(20, 90, 200), width=2)
    labels = [("robot start", (start.x, start.y - 0.45, 0.01), (20, 90, 200))]
    for spec in setup.items:
        (x, y, z), _ = world.objects[spec.name].pose()
        labels.append((spec.name, (x, y, z + 0.12), (0, 0, 0)))
    labels += [(f"target: {spec.name}", (spec.target.x, spec.target.y, spec.target.z),
                (200, 30, 30)) for spec in setup.items]
    anchors = project(np.array([xyz for _, xyz, _ in labels]), width, height)
    for (text, _, colour), (u, v) in zip(labels, anchors, strict=True):
        _label(draw, text, float(u), float(v), colour, taken, width, height)
    return np.asarray(image)


def _label(draw, text: str, u: float, v: float, colour, taken: list, width: int,
           height: int) -> None:
    """A text box near (u, v), moved down past the boxes already drawn; a leader line
    when it moved."""
    left, top, right, bottom = draw.textbbox((0, 0), text)
    w, h = right - left + 6, bottom - top + 4
    x, y = min(max(0.0, u - w / 2), width - w), min(max(0.0, v - h - 4), height - h)
    start_y = y
    for _ in range(60):
        box = (x, y, x + w, y + h)
        if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3]
                   for b in taken):
            break
        y += h + 1
    if y > height - h:
        y = start_y
    taken.append((x, y, x + w, y + h))
    if abs(y - start_y) > 1:
        draw.line([(u, v), (x + w / 2, y)], fill=colour, width=1)
    draw.rectangle((x, y, x + w, y + h), fill=(255, 255, 255), outline=colour)
    draw.text((x + 3, y + 2 - top), text, fill=colour)


def save_png(image: np.ndarray, path: str | Path) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)
    return path
