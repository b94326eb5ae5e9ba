"""Labels on a picture of a setup: every item named, each target marked (a square on its
surface) and named, the robot's start marked; boxes moved down past the ones drawn, with
a leader line where one moved."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cramlite.world.setup import Setup

Project = Callable[[np.ndarray], np.ndarray]


def label_setup(image: np.ndarray, setup: Setup, positions: dict[str, tuple],
                project: Project) -> np.ndarray:
    """The picture with the setup's items (at `positions`), targets and the robot's start
    marked and labelled; `project` maps world points (n x 3) to pixels (n x 2)."""
    from PIL import Image, ImageDraw

    picture = Image.fromarray(image)
    width, height = picture.size
    draw = ImageDraw.Draw(picture)
    half = 0.05  # target square half side (m)
    taken: list[tuple[float, float, float, float]] = []
    for spec in setup.items:
        t = spec.target
        corners = np.array([[t.x - half, t.y - half, t.z], [t.x + half, t.y - half, t.z],
                            [t.x + half, t.y + half, t.z], [t.x - half, t.y + half, t.z]])
        draw.polygon([tuple(c) for c in project(corners)], outline=(200, 30, 30), width=2)
    start = setup.robot_start
    ring = np.array([[start.x + 0.45 * np.cos(a), start.y + 0.45 * np.sin(a), 0.01]
                     for a in np.linspace(0, 2 * np.pi, 33)])
    draw.line([tuple(c) for c in project(ring)], fill=(20, 90, 200), width=2)
    labels = [("robot start", (start.x, start.y - 0.45, 0.01), (20, 90, 200))]
    for spec in setup.items:
        x, y, z = positions[spec.name]
        labels.append((spec.name, (x, y, z + 0.12), (0, 0, 0)))
    labels += [(f"target: {spec.name}", (spec.target.x, spec.target.y, spec.target.z),
                (200, 30, 30)) for spec in setup.items]
    anchors = project(np.array([xyz for _, xyz, _ in labels]))
    for (text, _, colour), (u, v) in zip(labels, anchors, strict=True):
        _label(draw, text, float(u), float(v), colour, taken, width, height)
    return np.asarray(picture)


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


