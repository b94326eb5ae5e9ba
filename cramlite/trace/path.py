"""A driven base path, compact: the executed base positions, simplified.

`simplify_path` drops the points that lie within `tolerance_m` of the straight line
between the points kept around them (Douglas-Peucker) and rounds to the centimetre. The
executed states of a trial (2 cm apart) become a few dozen points (a short JSON list in
each bench row), drawn within about a centimetre of where the robot drove.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

TOLERANCE_M = 0.01


def simplify_path(points: Iterable[Sequence[float]], tolerance_m: float = TOLERANCE_M,
                  ) -> list[list[float]]:
    """[[x, y], ...] in metres (rounded to 0.01) of the polyline through `points`."""
    xy = np.asarray([(float(p[0]), float(p[1])) for p in points], dtype=float).reshape(-1, 2)
    if len(xy) == 0:
        return []
    moved = np.r_[True, np.any(np.diff(xy, axis=0) != 0, axis=1)]
    xy = xy[moved]  # standing still (turning on the spot) adds nothing
    keep = _douglas_peucker(xy, tolerance_m)
    out: list[list[float]] = []
    for x, y in xy[keep]:
        point = [round(float(x), 2) + 0.0, round(float(y), 2) + 0.0]
        if not out or point != out[-1]:
            out.append(point)
    return out


def _douglas_peucker(xy: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the points to keep (iterative, so any length works)."""
    n = len(xy)
    if n <= 2:
        return np.arange(n)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        start, end = xy[a], xy[b]
        seg = end - start
        length = float(np.hypot(*seg))
        inner = xy[a + 1:b] - start
        if length == 0.0:
            dist = np.hypot(inner[:, 0], inner[:, 1])
        else:
            dist = np.abs(seg[0] * inner[:, 1] - seg[1] * inner[:, 0]) / length
        k = int(np.argmax(dist))
        if dist[k] > tolerance:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return np.flatnonzero(keep)
