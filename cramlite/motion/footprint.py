"""A 2D map of the fixed world and the PR2's square footprint, for base planning.

Checking the footprint against a precomputed occupancy grid costs microseconds, where a
PyBullet query per state would cost milliseconds (shared/PITFALLS.md). Fixed geometry
is every environment link that rises above the floor; carried objects are extra points
outlining their real footprint in the robot's frame, checked against the furniture that
rises above their lowest point.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from cramlite.world.pr2 import PR2_BASE_HALF_SIZE_M

#: Base poses whose answer a checker remembers at most (then it starts afresh).
KNOWN_POSES = 200_000
#: Links lower than this are floor, not obstacles.
FLOOR_HEIGHT_M = 0.03


@dataclass(frozen=True)
class Bounds2D:
    x_min: float
    x_max: float
    y_min: float
    y_max: float


class OccupancyMap:
    """Boolean grid of the fixed world, inflated by a safety margin."""

    def __init__(self, boxes: Iterable[tuple[str, Sequence[float], Sequence[float]]],
                 resolution_m: float = 0.01, margin_m: float = 0.02,
                 min_top_m: float = FLOOR_HEIGHT_M):
        """`min_top_m`: only links whose top is higher count (a map for carried objects
        held above the counters uses their height)."""
        boxes = list(boxes)
        floor = [b for b in boxes if b[2][2] <= FLOOR_HEIGHT_M]
        obstacles = [b for b in boxes if b[2][2] > max(min_top_m, FLOOR_HEIGHT_M)]
        source = floor or obstacles
        self.bounds = Bounds2D(min(b[1][0] for b in source), max(b[2][0] for b in source),
                               min(b[1][1] for b in source), max(b[2][1] for b in source))
        self.resolution = resolution_m
        self.margin = margin_m
        nx = math.ceil((self.bounds.x_max - self.bounds.x_min) / resolution_m) + 1
        ny = math.ceil((self.bounds.y_max - self.bounds.y_min) / resolution_m) + 1
        grid = np.zeros((nx, ny), dtype=bool)
        for _, lo, hi in obstacles:
            i0, j0 = self._cell(lo[0], lo[1])
            i1, j1 = self._cell(hi[0], hi[1])
            grid[max(i0, 0):max(i1 + 1, 0), max(j0, 0):max(j1 + 1, 0)] = True
        self.obstacles = grid
        if margin_m > 0:
            radius = math.ceil(margin_m / resolution_m)
            yy, xx = np.mgrid[-radius:radius + 1, -radius:radius + 1]
            disk = xx**2 + yy**2 <= radius**2
            grid = ndimage.binary_dilation(grid, structure=disk)
        self.blocked = grid

    @functools.cached_property
    def clearance(self) -> np.ndarray:
        """Distance (m) from each cell to the nearest obstacle cell (before inflation);
        computed when first asked for (maps for carried objects never need it)."""
        return ndimage.distance_transform_edt(~self.obstacles) * self.resolution

    def clearance_at(self, x: float, y: float) -> float:
        i, j = self._cell(x, y)
        if 0 <= i < self.clearance.shape[0] and 0 <= j < self.clearance.shape[1]:
            return float(self.clearance[i, j])
        return 0.0

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return (int(round((x - self.bounds.x_min) / self.resolution)),
                int(round((y - self.bounds.y_min) / self.resolution)))

    def blocked_at(self, xy: np.ndarray) -> np.ndarray:
        """True for points (N x 2) on blocked cells or outside the map."""
        idx = np.rint((xy - (self.bounds.x_min, self.bounds.y_min)) / self.resolution).astype(int)
        inside = ((idx[:, 0] >= 0) & (idx[:, 0] < self.blocked.shape[0])
                  & (idx[:, 1] >= 0) & (idx[:, 1] < self.blocked.shape[1]))
        out = np.ones(len(xy), dtype=bool)
        out[inside] = self.blocked[idx[inside, 0], idx[inside, 1]]
        return out


def square_outline(half_size: float, spacing: float) -> np.ndarray:
    """Points along the edge of a square centred at the origin (robot frame)."""
    n = max(2, math.ceil(2 * half_size / spacing) + 1)
    t = np.linspace(-half_size, half_size, n)
    edges = [np.column_stack([t, np.full(n, s)]) for s in (-half_size, half_size)]
    edges += [np.column_stack([np.full(n, s), t]) for s in (-half_size, half_size)]
    return np.vstack(edges)


class FootprintChecker:
    """Is the robot (square base, and whatever sticks out of it: carried objects, arm
    links) clear of the fixed world at (x, y, yaw)? What sticks out is checked against
    the furniture tall enough to reach it (`set_carried`).
    """

    def __init__(self, occupancy: OccupancyMap, half_size_m: float = PR2_BASE_HALF_SIZE_M,
                 outline_spacing_m: float = 0.04):
        self.occupancy = occupancy
        self.outline = square_outline(half_size_m, outline_spacing_m)
        self.half_size_m = half_size_m
        self.carried_groups: list[tuple[np.ndarray, OccupancyMap, float]] = []
        #: An exact check of what sticks out (robot links, carried objects) at a base pose,
        #: consulted where the 2D outlines say blocked (see `set_carried`).
        self.exact: Callable[[float, float, float], bool] | None = None
        self._known: dict[tuple, bool] = {}
        self.checks = 0
        pad = occupancy.margin + occupancy.resolution
        self._sure_free = half_size_m * math.sqrt(2) + pad  # circumscribed circle clear
        self._sure_blocked = half_size_m - pad  # something inside the inscribed circle

    def set_carried(self, groups: Sequence[tuple[Sequence[Sequence[float]],
                                                  OccupancyMap | None]],
                    exact: Callable[[float, float, float], bool] | None = None) -> None:
        """What sticks out of the base while driving: groups of robot-frame xy points
        outlining a carried object or an arm's link, each with the map of what it can touch
        at its height (None: the full map). Empty when nothing sticks out. `exact(x, y,
        yaw)`: the precise check to consult where an outline touches the furniture."""
        pad = self.occupancy.margin + self.occupancy.resolution
        self._known.clear()
        self.exact = exact
        self.carried_groups = []
        for points, occupancy in groups:
            pts = np.asarray(points, dtype=float).reshape(-1, 2)
            if len(pts):  # (points, map, how far they reach from the base's centre)
                self.carried_groups.append((pts, occupancy or self.occupancy,
                                            float(np.hypot(*pts.T).max()) + pad))

    def is_free(self, x: float, y: float, yaw: float) -> bool:
        """Is the robot clear of the world at this base pose? (Answers are remembered
        until what the robot carries changes: location designators ask about the same
        poses again and again.)"""
        key = (id(self.occupancy), round(x, 5), round(y, 5), round(yaw, 5))
        known = self._known.get(key)
        if known is None:
            if len(self._known) > KNOWN_POSES:
                self._known.clear()
            known = self._known[key] = self._is_free(x, y, yaw)
        return known

    def _is_free(self, x: float, y: float, yaw: float) -> bool:
        self.checks += 1
        clearance = self.occupancy.clearance_at(x, y)
        if clearance < self._sure_blocked:
            return False
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, s], [-s, c]])
        # each part is checked only if something it can touch is within its reach
        if clearance <= self._sure_free and \
                self.occupancy.blocked_at(self.outline @ rotation + (x, y)).any():
            return False
        for points, occupancy, reach in self.carried_groups:
            if clearance > reach:  # (the full map's clearance: no less than its own)
                continue
            if occupancy.blocked_at(points @ rotation + (x, y)).any():
                # the outlines over-approximate an arm; the exact check decides, if given
                return self.exact is not None and self.exact(x, y, yaw)
        return True
