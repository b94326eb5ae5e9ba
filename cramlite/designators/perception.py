"""Simulated perception: `DetectAction` reports the items the head camera sees now.

An item is seen if a point of it (the middle of its bounds, or the middle of its top)
lies inside the camera's view (`high_def_frame`, looking along its x axis; a field of
view of FOV_H_DEG x FOV_V_DEG, between NEAR_M and FAR_M) and the straight line from the
camera to that point passes through no kitchen shape and no other item, as the planning
scene believes them to stand (an open cupboard door no longer hides what is behind it).
Shapes are taken by their bounding boxes in their own frames: exact for the kitchen's
boxes, a little generous for cylinders. The robot does not hide anything from itself
(the camera sits above its arms when they are parked).

A detection may add seeded noise to the poses it reports (`noise_m`, from a random stream
of its own, so that planning's random choices do not shift).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import ObjectNotFound
from cramlite.designators.head import GAZE_FRAME
from cramlite.designators.tasks import ActionDesignator

#: The camera's view (an assumption: about the PR2's wide-angle stereo pair).
FOV_H_DEG = 70.0
FOV_V_DEG = 55.0
NEAR_M, FAR_M = 0.1, 5.0
#: The line of sight stops this short of its ends (the point sits on its own surface).
SIGHT_MARGIN_M = 0.01


def _boxes(ctx: RobotContext, skip_item: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """(4 x 4 placement of the box's centre, half sizes) of every kitchen shape and every
    other item's shape, as believed."""
    out = []
    for shape, placement in ctx.scene.kitchen_shapes():
        centre = placement.copy()
        centre[:3, 3] = placement[:3, :3] @ shape.centre + placement[:3, 3]
        out.append((centre, np.asarray(shape.half, dtype=float)))
    for name, item in ctx.scene.items.items():
        if name == skip_item:
            continue
        frame = ctx.scene.item_matrix(name)
        for shape in item.model.shapes:
            placement = frame @ shape.in_link
            centre = placement.copy()
            centre[:3, 3] = placement[:3, :3] @ shape.centre + placement[:3, 3]
            out.append((centre, np.asarray(shape.half, dtype=float)))
    return out


def _segment_hits_box(start: np.ndarray, end: np.ndarray, box: np.ndarray,
                      half: np.ndarray) -> bool:
    """Does the segment cross the box (slab test in the box's frame)?"""
    rotation, centre = box[:3, :3], box[:3, 3]
    a = rotation.T @ (start - centre)
    d = rotation.T @ (end - start)
    t0, t1 = 0.0, 1.0
    for k in range(3):
        if abs(d[k]) < 1e-12:
            if abs(a[k]) > half[k]:
                return False
            continue
        lo, hi = (-half[k] - a[k]) / d[k], (half[k] - a[k]) / d[k]
        lo, hi = min(lo, hi), max(lo, hi)
        t0, t1 = max(t0, lo), min(t1, hi)
        if t0 > t1:
            return False
    return True


def in_view(camera: np.ndarray, point: np.ndarray) -> bool:
    """Is the point inside the camera's field of view and range?"""
    local = camera[:3, :3].T @ (point - camera[:3, 3])
    if not NEAR_M <= local[0] <= FAR_M:
        return False
    return (abs(math.degrees(math.atan2(local[1], local[0]))) <= FOV_H_DEG / 2
            and abs(math.degrees(math.atan2(local[2], local[0]))) <= FOV_V_DEG / 2)


def sees(ctx: RobotContext, name: str) -> bool:
    """Does the head camera see the item now (see the module's doc)?"""
    camera = ctx.scene.link_matrix(GAZE_FRAME)
    frame = ctx.scene.item_matrix(name)
    _, _, height = ctx.scene.items[name].extents
    points = [frame[:3, :3] @ np.array([0.0, 0.0, z]) + frame[:3, 3]
              for z in (height / 2, height)]
    boxes = _boxes(ctx, name)
    eye = camera[:3, 3]
    for point in points:
        if not in_view(camera, point):
            continue
        direction = point - eye
        length = float(np.linalg.norm(direction))
        if length <= 2 * SIGHT_MARGIN_M:
            return True
        unit = direction / length
        start, end = eye + unit * SIGHT_MARGIN_M, point - unit * SIGHT_MARGIN_M
        if not any(_segment_hits_box(start, end, box, half) for box, half in boxes):
            return True
    return False


@dataclass
class DetectAction(ActionDesignator):
    """The items the head camera sees now, with their poses (as perceived: the scene's
    belief, plus seeded noise of `noise_m` standard deviation per axis if asked). With
    `object`, that item must be among them (else ObjectNotFound)."""

    object: str | None = None
    noise_m: float = 0.0
    seed: int = 0
    _rng: Any = field(default=None, init=False, repr=False)

    def execute(self, ctx: RobotContext) -> dict[str, tuple[tuple[float, ...], tuple]]:
        if self._rng is None:
            self._rng = np.random.default_rng([self.seed, 3])  # (a stream of its own)
        seen: dict[str, tuple[tuple[float, ...], tuple]] = {}
        if ctx.injector is not None and ctx.injector.fails("detect"):
            return seen  # (injected: the camera saw nothing this time)
        for name in ctx.scene.items:
            if name in ctx.scene.held or not sees(ctx, name):
                continue
            position, orientation = ctx.scene.object_pose(name)
            if self.noise_m > 0:
                position = tuple(float(v) for v in
                                 np.asarray(position) + self._rng.normal(0, self.noise_m, 3))
            seen[name] = (tuple(position), tuple(orientation))
        return seen

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        if self.object is not None and self.object not in (result or {}):
            raise ObjectNotFound(f"{self.object} is not in view of the head camera",
                                 obj=self.object)
