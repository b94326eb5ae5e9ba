"""A driven base path, compact: the executed base positions thinned to a few per metre.

`simplify_path` keeps a point every `spacing_m` along the path (and the last one), then
drops the points that lie within `tolerance_m` of the straight line between their
neighbours (Douglas-Peucker), and rounds to the centimetre. A 15 m path of a trial
becomes a few dozen points (a short JSON list in each bench row), drawn within a
centimetre of where the robot drove.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

SPACING_M = 0.05
TOLERANCE_M = 0.01


def simplify_path(points: Iterable[Sequence[float]], spacing_m: float = SPACING_M,
                  tolerance_m: float = TOLERANCE_M) -> list[list[float]]:
    """[[x, y], ...] in metres (rounded to 0.01) of the polyline through `points`."""
    xy = np.asarray([(float(p[0]), float(p[1])) for p in points], dtype=float)
    if len(xy) == 0:
        return []
    kept = [xy[0]]
    for point in xy[1:]:
        if np.hypot(*(point - kept[-1])) >= spacing_m:
            kept.append(point)
    if len(xy) > 1 and np.hypot(*(xy[-1] - kept[-1])) > 0:
        kept.append(xy[-1])
    thinned = np.array(kept)
    keep = _douglas_peucker(thinned, tolerance_m)
    out: list[list[float]] = []
    for x, y in thinned[keep]:
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
