"""A small software rasteriser: flat-shaded triangles with a depth buffer, in numpy.

It draws cramlite's scenes (a few thousand triangles: the PR2's collision meshes, the
kitchen's and the items' boxes and cylinders) at a few hundred pixels a side for
pictures and replays without a simulator or an OpenGL context. Large triangles are
split; the pixels each triangle covers are found by scan lines for all triangles at
once, and the nearest fragment of each pixel wins.
"""

from __future__ import annotations

import numpy as np

from cramlite.render.camera import NEAR_M, Camera

#: Triangles are split until their pixel bounds are at most this many pixels a side (their
#: depth is interpolated on the screen: small ones keep it close to the true one).
MAX_SIDE_PX = 96
#: Light direction (towards the light) and the share of ambient light.
LIGHT = np.array([-0.4, 0.6, 1.0]) / np.linalg.norm([-0.4, 0.6, 1.0])
AMBIENT = 0.45
BACKGROUND = (235, 235, 232)


def shade(triangles: np.ndarray, colours: np.ndarray) -> np.ndarray:
    """Flat Lambert shading (either side of a triangle lit alike: meshes are not all wound
    one way)."""
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(normal, axis=1)
    normal = normal / np.where(length > 0, length, 1.0)[:, None]
    light = AMBIENT + (1 - AMBIENT) * np.abs(normal @ LIGHT)
    return np.clip(colours * light[:, None], 0.0, 1.0)


def rasterise(triangles: np.ndarray, colours: np.ndarray, camera: Camera, width: int,
              height: int) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) of world triangles (T x 3 x 3) with their
    colours (T x 3, in 0..1)."""
    image = np.empty((height * width, 3), dtype=np.uint8)
    image[:] = BACKGROUND
    if not len(triangles):
        return image.reshape(height, width, 3)
    shaded = shade(triangles, colours)
    projected = camera.pixels(triangles.reshape(-1, 3), width, height).reshape(-1, 3, 3)
    visible = np.all(projected[:, :, 2] > NEAR_M, axis=1)
    triangles, shaded, projected = triangles[visible], shaded[visible], projected[visible]
    # split what is large on screen (in the world: depth stays right) until it is small
    for _ in range(12):
        span = projected[:, :, :2].max(axis=1) - projected[:, :, :2].min(axis=1)
        big = np.any(span > MAX_SIDE_PX, axis=1)
        big &= np.all(np.abs(projected[:, :, :2]) < 4 * max(width, height), axis=(1, 2))
        if not big.any():
            break
        parts = _split(triangles[big])
        triangles = np.concatenate([triangles[~big], parts])
        shaded = np.concatenate([shaded[~big], np.repeat(shaded[big], 4, axis=0)])
        projected = np.concatenate([projected[~big], camera.pixels(
            parts.reshape(-1, 3), width, height).reshape(-1, 3, 3)])
    pixel, depth, colour = _fragments(projected, shaded, width, height)
    if len(pixel):
        # farthest first: where a pixel is written more than once, the last value stays
        # (numpy's rule for repeated indices), so the nearest fragment wins
        order = np.argsort(-depth, kind="stable")
        image[pixel[order]] = (colour[order] * 255).astype(np.uint8)
    return image.reshape(height, width, 3)


def _split(triangles: np.ndarray) -> np.ndarray:
    """Each triangle in four, at the midpoints of its sides."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    return np.stack([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c),
                                                    (ab, bc, ca))], axis=1).reshape(-1, 3, 3)


def _fragments(projected: np.ndarray, colours: np.ndarray, width: int, height: int,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pixel index, depth, colour) of every pixel centre inside a triangle, by scan
    lines: for every row a triangle spans, where its edges cross the row's centre line
    bounds the run of pixels it covers; its depth follows the triangle's plane on the
    screen (all triangles and rows at once)."""
    x, y, z = projected[:, :, 0], projected[:, :, 1], projected[:, :, 2]
    # depth = p x + q y + r over each triangle's screen projection
    dx1, dy1, dz1 = x[:, 1] - x[:, 0], y[:, 1] - y[:, 0], z[:, 1] - z[:, 0]
    dx2, dy2, dz2 = x[:, 2] - x[:, 0], y[:, 2] - y[:, 0], z[:, 2] - z[:, 0]
    det = dx1 * dy2 - dx2 * dy1
    flat = np.abs(det) > 1e-9
    x, y, z = x[flat], y[flat], z[flat]
    colours, det = colours[flat], det[flat]
    dx1, dy1, dz1, dx2, dy2, dz2 = (v[flat] for v in (dx1, dy1, dz1, dx2, dy2, dz2))
    p = (dz1 * dy2 - dz2 * dy1) / det
    q = (dx1 * dz2 - dx2 * dz1) / det
    r = z[:, 0] - p * x[:, 0] - q * y[:, 0]
    first = np.maximum(np.ceil(y.min(axis=1) - 0.5), 0).astype(np.int64)
    last = np.minimum(np.floor(y.max(axis=1) - 0.5), height - 1).astype(np.int64)
    rows = np.maximum(last - first + 1, 0)
    t = np.repeat(np.arange(len(rows)), rows)
    row = first[t] + np.arange(rows.sum()) - np.repeat(np.cumsum(rows) - rows, rows)
    centre = row + 0.5
    low, high = np.full(len(t), np.inf), np.full(len(t), -np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        ya, yb, xa, xb = y[t, a], y[t, b], x[t, a], x[t, b]
        crosses = (np.minimum(ya, yb) <= centre) & (centre <= np.maximum(ya, yb)) & (ya != yb)
        at = xa + (centre - ya) * (xb - xa) / np.where(ya != yb, yb - ya, 1.0)
        low = np.where(crosses, np.minimum(low, at), low)
        high = np.where(crosses, np.maximum(high, at), high)
    start = np.maximum(np.ceil(low - 0.5), 0)
    stop = np.minimum(np.floor(high - 0.5), width - 1)
    runs = np.where(np.isfinite(start) & np.isfinite(stop), stop - start + 1, 0)
    runs = np.maximum(runs, 0).astype(np.int64)
    which = np.repeat(np.arange(len(runs)), runs)
    column = start[which].astype(np.int64) + np.arange(runs.sum()) - np.repeat(
        np.cumsum(runs) - runs, runs)
    tri = t[which]
    line = row[which]
    depth = p[tri] * (column + 0.5) + q[tri] * (line + 0.5) + r[tri]
    return line * width + column, depth, colours[tri]
