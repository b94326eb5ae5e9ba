"""Exact geometric tests on shapes that coal does not offer: is a point inside a mesh, how
deep are points inside a box or a cylinder, surface samples of a mesh.

coal's mesh tests see surfaces that cross; a mesh wholly inside another mesh, or a box
inside a mesh, crosses no surface. The generalised winding number (Jacobson et al. 2013:
the solid angles of the triangles seen from the point, over 4 pi) is 1 inside a closed
mesh and 0 outside, and degrades gracefully where a mesh has holes (several PR2 meshes
do), so it is the inside test here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import coal
import numpy as np

from cramlite.scene.models import BOX, CYLINDER, MESH, SPHERE, Shape


class PointGrid:
    """Points with a grid index, for the ones within a box: a big link's surface is covered
    by 100 000 points about a centimetre apart, of which a contact needs a few."""

    CELL_M = 0.04

    def __init__(self, points: np.ndarray):
        keys = np.floor(points / self.CELL_M).astype(np.int64)
        self._origin = keys.min(axis=0) if len(keys) else np.zeros(3, dtype=np.int64)
        keys -= self._origin
        dims = keys.max(axis=0) + 1 if len(keys) else np.ones(3, dtype=np.int64)
        flat = (keys[:, 0] * dims[1] + keys[:, 1]) * dims[2] + keys[:, 2]
        order = np.argsort(flat, kind="stable")
        self.points, flat = points[order], flat[order]
        cells, starts, counts = np.unique(flat, return_index=True, return_counts=True)
        self.keys = np.column_stack(np.unravel_index(cells, tuple(dims)))
        self.spans = np.column_stack([starts, starts + counts])
        self.point_cell = np.repeat(np.arange(len(cells)), counts)

    def within(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        first = np.floor(lo / self.CELL_M).astype(np.int64) - self._origin
        last = np.floor(hi / self.CELL_M).astype(np.int64) - self._origin
        cells = np.all((self.keys >= first) & (self.keys <= last), axis=1)
        chosen = np.flatnonzero(cells)
        if not len(chosen):
            return np.zeros((0, 3))
        if len(chosen) <= 8:
            points = np.vstack([self.points[a:b] for a, b in self.spans[chosen]])
        else:
            points = self.points[cells[self.point_cell]]
        return points[np.all((points >= lo - 1e-9) & (points <= hi + 1e-9), axis=1)]


def winding_numbers(points: np.ndarray, vertices: np.ndarray,
                    triangles: np.ndarray) -> np.ndarray:
    """The generalised winding number of each point (N x 3) w.r.t. a mesh (shape frame):
    the sum of the triangles' solid angles seen from the point (Van Oosterom and
    Strackee's formula), over 4 pi; all points and triangles at once, in chunks."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    tri = vertices[triangles]  # T x 3 x 3
    out = np.empty(len(points))
    chunk = max(1, 200_000 // max(1, len(tri)))
    for start in range(0, len(points), chunk):
        rel = tri[None] - points[start:start + chunk, None, None, :]  # N x T x 3 x 3
        a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
        la, lb, lc = (np.sqrt((v * v).sum(axis=2)) for v in (a, b, c))
        cross = np.stack([b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1],
                          b[..., 2] * c[..., 0] - b[..., 0] * c[..., 2],
                          b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]], axis=-1)
        det = (a * cross).sum(axis=2)
        dot = (la * lb * lc + (a * b).sum(axis=2) * lc + (a * c).sum(axis=2) * lb
               + (b * c).sum(axis=2) * la)
        out[start:start + chunk] = np.arctan2(det, dot).sum(axis=1) / (2 * math.pi)
    return out


def inside_mesh(points: np.ndarray, shape: Shape) -> np.ndarray:
    """Which points (N x 3, shape frame) lie inside a mesh shape (winding number > 1/2)."""
    return np.abs(winding_numbers(points, shape.vertices, shape.triangles)) > 0.5


def primitive_depth(points: np.ndarray, shape: Shape) -> np.ndarray:
    """How deep each point (N x 3, shape frame) is inside a box, cylinder or sphere (m;
    0 outside)."""
    p = np.atleast_2d(points) - shape.centre
    if shape.kind == BOX:
        inner = shape.half - np.abs(p)
        return np.maximum(inner.min(axis=1), 0.0)
    if shape.kind == CYLINDER:
        radial = shape.half[0] - np.hypot(p[:, 0], p[:, 1])
        axial = shape.half[2] - np.abs(p[:, 2])
        return np.maximum(np.minimum(radial, axial), 0.0)
    if shape.kind == SPHERE:
        return np.maximum(shape.half[0] - np.linalg.norm(p, axis=1), 0.0)
    raise ValueError(f"not a primitive: {shape.kind}")


def surface_samples(shape: Shape, spacing: float) -> np.ndarray:
    """Points on a shape's surface (shape frame) at most about `spacing` apart: a mesh's
    vertices and points spread over each triangle; a primitive's corners, edges and
    faces."""
    if shape.kind == MESH:
        return triangle_samples(shape.vertices[shape.triangles], spacing)
    if shape.kind == BOX:
        axes = [np.linspace(-h, h, max(2, int(math.ceil(2 * h / spacing)) + 1))
                for h in shape.half]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        on_face = np.any(np.isclose(np.abs(grid), shape.half), axis=1)
        return grid[on_face] + shape.centre
    if shape.kind == CYLINDER:
        r, h = shape.half[0], shape.half[2]
        around = max(8, int(math.ceil(2 * math.pi * r / spacing)))
        angles = np.linspace(0, 2 * math.pi, around, endpoint=False)
        heights = np.linspace(-h, h, max(2, int(math.ceil(2 * h / spacing)) + 1))
        rim = np.array([[r * math.cos(a), r * math.sin(a), z] for z in heights
                        for a in angles])
        radii = np.linspace(0, r, max(2, int(math.ceil(r / spacing)) + 1))
        caps = np.array([[q * math.cos(a), q * math.sin(a), z] for z in (-h, h)
                         for q in radii for a in angles])
        return np.vstack([rim, caps]) + shape.centre
    r = shape.half[0]  # a sphere
    n = max(12, int(math.ceil(4 * math.pi * r * r / spacing ** 2)))
    k = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * k / n), math.pi * (1 + 5 ** 0.5) * k
    return np.column_stack([r * np.cos(theta) * np.sin(phi), r * np.sin(theta) * np.sin(phi),
                            r * np.cos(phi)]) + shape.centre


def triangle_samples(triangles: np.ndarray, spacing: float) -> np.ndarray:
    """Points over triangles (T x 3 x 3), each covered by a grid of barycentric steps of
    1/n (n: its longest side over `spacing`), corners included; triangles of one n at
    once."""
    sides = np.stack([np.linalg.norm(triangles[:, 1] - triangles[:, 0], axis=1),
                      np.linalg.norm(triangles[:, 2] - triangles[:, 1], axis=1),
                      np.linalg.norm(triangles[:, 0] - triangles[:, 2], axis=1)], axis=1)
    steps = np.maximum(1, np.ceil(sides.max(axis=1) / spacing)).astype(int)
    out = []
    for n in np.unique(steps):
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = (i + j) <= n
        u, v = i[keep] / n, j[keep] / n  # P
        group = triangles[steps == n]  # G x 3 x 3
        a, ab, ac = group[:, 0], group[:, 1] - group[:, 0], group[:, 2] - group[:, 0]
        out.append((a[:, None] + u[None, :, None] * ab[:, None]
                    + v[None, :, None] * ac[:, None]).reshape(-1, 3))
    return np.vstack(out)


def point_triangle_distances(points: np.ndarray, vertices: np.ndarray,
                             triangles: np.ndarray) -> np.ndarray:
    """Distance from each point (N x 3) to the nearest triangle of a mesh (N,): projected
    onto each triangle's plane where that falls inside it, else onto its edges."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    tri = vertices[triangles]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac = b - a, c - a
    normal = np.cross(ab, ac)
    area = (normal * normal).sum(axis=1)
    safe = np.where(area > 1e-30, area, 1.0)
    out = np.empty(len(points))
    chunk = max(1, 100_000 // max(1, len(tri)))
    for start in range(0, len(points), chunk):
        p = points[start:start + chunk, None, :]  # N x 1 x 3
        ap = p - a
        v = (np.cross(ap, ac) * normal).sum(axis=2) / safe
        w = (np.cross(ab, ap) * normal).sum(axis=2) / safe
        inside = (v >= 0) & (w >= 0) & (v + w <= 1) & (area > 1e-30)
        plane = (ap * normal).sum(axis=2) ** 2 / safe
        edges = np.minimum(np.minimum(_segment_sq(p, a, b), _segment_sq(p, b, c)),
                           _segment_sq(p, c, a))
        out[start:start + chunk] = np.sqrt(np.where(inside, plane, edges).min(axis=1))
    return out


def _segment_sq(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distances from points (N x 1 x 3) to segments a-b (T x 3): N x T."""
    ab = b - a
    length = (ab * ab).sum(axis=1)
    t = np.clip(((p - a) * ab).sum(axis=2) / np.where(length > 0, length, 1.0), 0, 1)
    d = a + t[..., None] * ab - p
    return (d * d).sum(axis=2)


def convex_hull_planes(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The outward unit normals (F x 3) and offsets (F) of the convex hull of points:
    inside, n.x + d <= 0. (coal's qhull, which the scene links anyway: scipy.spatial's
    import costs 0.08 s a process.)"""
    points = coal.StdVec_Vec3s()
    for vertex in np.asarray(vertices, dtype=float):
        points.append(vertex)
    hull = coal.Convex.convexHull(points, True, None)
    return np.array(hull.normals(), dtype=float), np.array(hull.offsets(), dtype=float)


def boxes_apart(axes_a: np.ndarray, centres_a: np.ndarray, halves_a: np.ndarray,
                axes_b: np.ndarray, centres_b: np.ndarray, halves_b: np.ndarray,
                gap: float) -> np.ndarray:
    """Which of M pairs of oriented boxes are more than `gap` apart along one of the
    boxes' six face normals (bool, M): the face axes of the separating-axis test
    (Gottschalk et al. 1996; Ericson, Real-Time Collision Detection 4.4.1). Axes are the
    columns of the M x 3 x 3 rotations, centres and half sizes M x 3. True only for boxes
    that are apart (so the shapes inside them are); the nine edge-edge axes are left out:
    they find a few more separations at three times the cost."""
    turned = axes_a.transpose(0, 2, 1)
    r = turned @ axes_b  # R[i, k] = a_i . b_k
    t = (turned @ (centres_b - centres_a)[:, :, None])[..., 0]  # in a's frame
    ar = np.abs(r) + 1e-9
    apart = (np.abs(t) > halves_a + (ar @ halves_b[:, :, None])[..., 0] + gap).any(axis=1)
    t_b = (t[:, None, :] @ r)[:, 0]
    apart |= (np.abs(t_b) > (halves_a[:, None, :] @ ar)[:, 0] + halves_b + gap).any(axis=1)
    return apart


def placed_bounds(shapes: Sequence[Shape], placements: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds (lo, hi: N x 3) of placed shapes (their local bounds turned)."""
    if not len(shapes):
        return np.zeros((0, 3)), np.zeros((0, 3))
    return bounds_at(np.array([s.centre for s in shapes]), np.array([s.half for s in shapes]),
                     placements)


def bounds_at(centres: np.ndarray, halves: np.ndarray, placements: np.ndarray,
              ) -> tuple[np.ndarray, np.ndarray]:
    """`placed_bounds` of shapes given by their local bounds' centres and half sizes (N x 3)."""
    rotations = placements[:, :3, :3]
    mid = (rotations @ centres[:, :, None])[:, :, 0] + placements[:, :3, 3]
    span = (np.abs(rotations) @ halves[:, :, None])[:, :, 0]
    return mid - span, mid + span


def depth_text(depth_m: float) -> str:
    """A penetration's depth for a message: in cm from 1 cm, below that in mm (a depth
    under the tolerance of `replay --check --tolerance-cm 0.01` read "0.0 cm")."""
    if depth_m >= 0.00995:
        return f"{depth_m * 100:.1f} cm"
    mm = depth_m * 1000
    return f"{mm:.1f} mm" if mm >= 0.0995 else f"{mm:.2g} mm"
