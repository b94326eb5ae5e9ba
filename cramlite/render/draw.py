"""The triangles of a scene to draw: the kitchen, the items and the PR2, coloured.

Shapes are the scene's collision shapes (the PR2's real collision meshes, the kitchen's
and the items' boxes and cylinders), coloured as the URDFs' visual materials colour their
links; each shape's triangles in its own frame are made once and placed per picture.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pinocchio as pin

from cramlite.scene.models import BOX, CYLINDER, MESH, SPHERE, ArticulatedModel, Shape
from cramlite.scene.scene import PlanningScene

#: Colour of a link whose URDF gives none.
DEFAULT_COLOUR = (0.6, 0.6, 0.62)
CYLINDER_SEGMENTS = 24


@functools.cache
def link_colours(model: ArticulatedModel) -> dict[str, tuple[float, float, float]]:
    """Each link's colour: its first visual geometry's material (RGB)."""
    try:
        visual = pin.buildGeomFromUrdf(model.model, str(model.urdf), pin.GeometryType.VISUAL,
                                       package_dirs=model.package_dirs)
    except (ValueError, RuntimeError):
        return {}
    out: dict[str, tuple[float, float, float]] = {}
    for go in visual.geometryObjects:
        link = model.model.frames[go.parentFrame].name
        colour = tuple(float(v) for v in go.meshColor[:3])
        if link not in out and colour != (1.0, 1.0, 1.0):
            out[link] = colour
    return out


@functools.cache
def _local_triangles(shape: Shape) -> np.ndarray:
    """A shape's triangles (T x 3 x 3) in its own frame."""
    if shape.kind == MESH:
        return shape.vertices[shape.triangles]
    if shape.kind == BOX:
        h = shape.half
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                            for sz in (-1, 1)]) * h + shape.centre
        faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                 (1, 5, 7, 3)]
        return np.array([corners[[a, b, c]] for q in faces for a, b, c in
                         ((q[0], q[1], q[2]), (q[0], q[2], q[3]))])
    if shape.kind == CYLINDER:
        r, h = shape.half[0], shape.half[2]
        angles = np.linspace(0, 2 * math.pi, CYLINDER_SEGMENTS, endpoint=False)
        ring = np.c_[r * np.cos(angles), r * np.sin(angles)]
        out = []
        for k in range(CYLINDER_SEGMENTS):
            a, b = ring[k], ring[(k + 1) % CYLINDER_SEGMENTS]
            lo_a, lo_b = [*a, -h], [*b, -h]
            hi_a, hi_b = [*a, h], [*b, h]
            out += [[lo_a, lo_b, hi_b], [lo_a, hi_b, hi_a], [[0, 0, h], hi_a, hi_b],
                    [[0, 0, -h], lo_b, lo_a]]
        return np.array(out, dtype=float) + shape.centre
    if shape.kind == SPHERE:  # an octahedron split twice, pushed onto the sphere
        tri = np.array([[a, b, c] for a in ([1, 0, 0], [-1, 0, 0]) for b in ([0, 1, 0],
                        [0, -1, 0]) for c in ([0, 0, 1], [0, 0, -1])], dtype=float)
        for _ in range(2):
            a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
            ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
            tri = np.concatenate([np.stack(t, axis=1) for t in
                                  ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
        tri /= np.linalg.norm(tri, axis=2, keepdims=True)
        return tri * shape.half[0] + shape.centre
    return np.zeros((0, 3, 3))


def placed(shape: Shape, placement: np.ndarray) -> np.ndarray:
    return _local_triangles(shape) @ placement[:3, :3].T + placement[:3, 3]


def scene_triangles(scene: PlanningScene) -> tuple[np.ndarray, np.ndarray]:
    """(triangles T x 3 x 3, colours T x 3) of the kitchen, the items and the robot as
    the scene believes them to be (the floor left out: the background shows it)."""
    parts, colours = [], []

    def add(shape: Shape, placement: np.ndarray, colour) -> None:
        tri = placed(shape, placement)
        parts.append(tri)
        colours.append(np.broadcast_to(np.asarray(colour, dtype=float), (len(tri), 3)))

    kitchen_colours = link_colours(scene.kitchen)
    for shape, placement in scene.kitchen_shapes():
        add(shape, placement, kitchen_colours.get(shape.link, DEFAULT_COLOUR))
    for name, item in scene.items.items():
        item_colours = link_colours(_item_articulated(item.model.urdf))
        colour = next(iter(item_colours.values()), DEFAULT_COLOUR)
        for shape, placement in scene.item_shapes(name):
            add(shape, placement, colour)
    robot_colours = link_colours(scene.robot)
    frames = scene.link_matrices(list(scene.robot.shapes_by_link))
    for link, shapes in scene.robot.shapes_by_link.items():
        for shape in shapes:
            add(shape, frames[link] @ shape.in_link, robot_colours.get(link, DEFAULT_COLOUR))
    return np.concatenate(parts), np.concatenate(colours)


@functools.cache
def _item_articulated(urdf) -> ArticulatedModel:
    return ArticulatedModel(urdf, [str(urdf.parent)])
