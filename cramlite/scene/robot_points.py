"""The robot's upper body as points: the vertices of its links' collision meshes, placed.

The base planner's 2D check counts what sticks out of the base (a parked PR2's elbows
reach 0.43 m beyond its sides) by these points seen from above; the carry pose is chosen
by how low they stick out. Everything is computed on the scene's model, for any joint
values, without moving anything.
"""

from __future__ import annotations

import functools

import numpy as np

from cramlite.scene.models import RobotModel
from cramlite.scene.scene import PlanningScene

TORSO = "torso_lift_joint"


@functools.cache
def _parts(robot: RobotModel) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
    out: dict[str, tuple[list[str], list[str]]] = {
        "right": ([TORSO] + [n for n in robot.joints if n.startswith("r_")], []),
        "left": ([TORSO] + [n for n in robot.joints if n.startswith("l_")], []),
        "body": ([TORSO], [])}
    for link, shapes in robot.shapes_by_link.items():
        above = robot.joints_above(link)
        if TORSO not in above or link == "torso_lift_link" or \
                not any(s.vertices is not None for s in shapes):
            continue
        part = ("right" if "r_shoulder_pan_joint" in above else
                "left" if "l_shoulder_pan_joint" in above else "body")
        out[part][1].append(link)
    return {k: (tuple(joints), tuple(links)) for k, (joints, links) in out.items()}


def upper_body_parts(scene: PlanningScene) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
    """The robot's links above its base with a collision mesh (torso itself aside), in
    three parts (each arm, and the rest: head, laser), each with the joints that place it."""
    return _parts(scene.robot)


def upper_body_points(scene: PlanningScene, links: tuple[str, ...] | list[str] | None = None,
                      joints: dict[str, float] | None = None,
                      base: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> list[np.ndarray]:
    """The mesh vertices (world) of robot links above the base (default: all of them), the
    robot as believed or with `joints`, its base at `base` (default: the origin)."""
    if links is None:
        links = [link for _, part in upper_body_parts(scene).values() for link in part]
    if not links:
        return []
    frames = scene.link_matrices(list(links), joints, base)
    out = []
    for link in links:
        for shape in scene.robot.shapes_by_link[link]:
            if shape.vertices is None:
                continue
            placement = frames[link] @ shape.in_link
            out.append(shape.vertices @ placement[:3, :3].T + placement[:3, 3])
    return out
