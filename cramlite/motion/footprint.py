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
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.world.pr2 import PR2_BASE_HALF_SIZE_M

#: Base poses whose answer a checker remembers at most (then it starts afresh).
KNOWN_POSES = 200_000
#: Base poses checked together by `FootprintChecker.all_free` (a path's first blocked
#: waypoint ends the check within a chunk).
BATCH_POSES = 32
#: Side of the cells of the clearance grid, in map cells (bounds within 6 cm).
COARSE_CELLS = 4
#: Maps with the items standing blocked on them that a footprint check keeps (a few
#: heights of what sticks out, by where the items stand).
STAMPED_MAPS = 64
#: The clearance grid knows distances up to this far (m); beyond, only that they are
#: farther (nothing a base check asks about reaches that far).
CLEARANCE_HORIZON_M = 2.0
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

    def __init__(self, boxes: Iterable[tuple], resolution_m: float = 0.01,
                 margin_m: float = 0.02, min_top_m: float = FLOOR_HEIGHT_M):
        """`boxes`: (name, lower corner, upper corner) of each link, optionally with a
        fourth element, the xy outlines (convex polygons) of a turned link, drawn instead of
        its axis-aligned bounds. `min_top_m`: only links whose top is higher count (a map
        for carried objects held above the counters uses their height)."""
        boxes = [tuple(b) if len(b) > 3 else (*b, None) for b in boxes]
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
        for _, lo, hi, outlines in obstacles:
            i0, j0 = self._cell(lo[0], lo[1])
            i1, j1 = self._cell(hi[0], hi[1])
            i0, j0, i1, j1 = max(i0, 0), max(j0, 0), max(i1 + 1, 0), max(j1 + 1, 0)
            if outlines is None:
                grid[i0:i1, j0:j1] = True
                continue
            xs = self.bounds.x_min + np.arange(i0, i1) * resolution_m
            ys = self.bounds.y_min + np.arange(j0, j1) * resolution_m
            cells = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1)
            for outline in outlines:
                grid[i0:i1, j0:j1] |= _inside(cells, outline, resolution_m * 0.71)
        self.obstacles = grid
        self.blocked = _dilated(grid, math.ceil(margin_m / resolution_m))

    @functools.cached_property
    def _coarse_clearance(self) -> np.ndarray:
        """Distance (m) between the centres of coarse cells (COARSE_CELLS map cells a side)
        and the nearest coarse cell holding an obstacle (before inflation), up to
        CLEARANCE_HORIZON_M (farther cells hold that value): computed when first asked for,
        on 1/16 of the cells (a map is made for every drawer position)."""
        f = COARSE_CELLS
        nx, ny = self.obstacles.shape
        cx, cy = -(-nx // f), -(-ny // f)
        padded = np.zeros((cx * f, cy * f), dtype=bool)
        padded[:nx, :ny] = self.obstacles
        rows = padded[0::f].copy()  # (or-ing strided slices: 20x faster than .any(axes))
        for k in range(1, f):
            rows |= padded[k::f]
        coarse = rows[:, 0::f].copy()
        for k in range(1, f):
            coarse |= rows[:, k::f]
        cell = f * self.resolution
        return distance_to_nearest(coarse, math.ceil(CLEARANCE_HORIZON_M / cell)) * cell

    def near(self, reach: float) -> np.ndarray:
        """Coarse cells from which an obstacle may be within `reach` (m)."""
        slack = COARSE_CELLS * self.resolution * math.sqrt(2)
        return self._coarse_clearance - slack <= reach

    def with_boxes(self, boxes: np.ndarray) -> OccupancyMap:
        """A copy of the map with these xy boxes [x0, y0, x1, y1] (world frame, K x 4)
        blocked too, grown by its margin (square at the corners: a little more than the
        furniture's disk), the same bounds and cells; its `near` is this map's (use
        `near_boxes` for the boxes). A few slices a box: items move, the kitchen's map
        (and its clearance) is drawn once."""
        blocked = self.blocked.copy()
        for i0, i1, j0, j1 in self._box_cells(boxes, self.margin):
            blocked[i0:i1 + 1, j0:j1 + 1] = True
        out = self._with_grids(self.obstacles, blocked)
        out.__dict__["_coarse_clearance"] = self._coarse_clearance
        return out

    @staticmethod
    def union(maps: Sequence[OccupancyMap]) -> OccupancyMap | None:
        """One map blocked wherever one of `maps` is (of the same bounds, cells and
        margin; None where they differ): a base pose is free on it exactly when it is free
        on each of them (a pose's points are the same on every map; the clearance bounds
        are the nearest of theirs), at the cost of one check (a drawer's or door's
        positions along its swing, say)."""
        first = maps[0]
        if any((m.bounds, m.resolution, m.margin, m.obstacles.shape) !=
               (first.bounds, first.resolution, first.margin, first.obstacles.shape)
               for m in maps):
            return None
        return first._with_grids(np.logical_or.reduce([m.obstacles for m in maps]),
                                 np.logical_or.reduce([m.blocked for m in maps]))

    def _with_grids(self, obstacles: np.ndarray, blocked: np.ndarray) -> OccupancyMap:
        """A map of this one's bounds, cells and margin with these grids (its clearance
        worked out from `obstacles` when first asked for)."""
        out = object.__new__(OccupancyMap)
        out.bounds, out.resolution, out.margin = self.bounds, self.resolution, self.margin
        out.obstacles, out.blocked = obstacles, blocked
        return out

    def near_boxes(self, boxes: np.ndarray, reach: float) -> np.ndarray:
        """Coarse cells (as `near`) from which one of these xy boxes [x0, y0, x1, y1] (K x
        4) may be within `reach` (m): each box grown by the reach and a coarse cell's
        diagonal, as a rectangle."""
        f = COARSE_CELLS
        nx, ny = self.obstacles.shape
        out = np.zeros((-(-nx // f), -(-ny // f)), dtype=bool)
        for i0, i1, j0, j1 in self._box_cells(boxes, reach + f * self.resolution *
                                              math.sqrt(2)):
            out[i0 // f:i1 // f + 1, j0 // f:j1 // f + 1] = True
        return out

    def _box_cells(self, boxes: np.ndarray, grow: float) -> Iterator[tuple[int, ...]]:
        """For each xy box [x0, y0, x1, y1] grown by `grow` (m) that meets the map: the
        first and last cell it covers along x and along y (i0, i1, j0, j1), within the
        map's cells from below (a slice's end past the map is cut by the slice)."""
        nx, ny = self.obstacles.shape
        for x0, y0, x1, y1 in np.asarray(boxes, dtype=float).reshape(-1, 4).tolist():
            i0, j0 = self._cell(x0 - grow, y0 - grow)
            i1, j1 = self._cell(x1 + grow, y1 + grow)
            if i1 >= 0 and j1 >= 0 and i0 < nx and j0 < ny:
                yield max(i0, 0), i1, max(j0, 0), j1

    def coarse_cell(self, x: float, y: float) -> tuple[int, int]:
        """The coarse cell of a point (-1, -1 outside the map)."""
        i, j = self._cell(x, y)
        if not (0 <= i < self.obstacles.shape[0] and 0 <= j < self.obstacles.shape[1]):
            return -1, -1
        return i // COARSE_CELLS, j // COARSE_CELLS

    def clearance_bounds(self, x: float, y: float) -> tuple[float, float]:
        """Lower and upper bounds (m) of the distance from (x, y) to the nearest obstacle
        (before inflation), within a coarse cell's diagonal; (0, 0) outside the map."""
        i, j = self._cell(x, y)
        if not (0 <= i < self.obstacles.shape[0] and 0 <= j < self.obstacles.shape[1]):
            return 0.0, 0.0
        f = COARSE_CELLS
        distance = float(self._coarse_clearance[i // f, j // f])
        slack = f * self.resolution * math.sqrt(2)
        upper = distance + slack if distance < CLEARANCE_HORIZON_M else math.inf
        return max(0.0, distance - slack), upper

    def coarse_cells_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`coarse_cell` of each point (N x 2): two index arrays, -1 outside the map."""
        cells = np.rint((xy - (self.bounds.x_min, self.bounds.y_min)) / self.resolution)
        inside = np.all((cells >= 0) & (cells < self.obstacles.shape), axis=1)
        # (compared as floats, cast where inside: a far point's index would overflow)
        cells = np.where(inside[:, None], cells, 0.0).astype(np.intp)
        coarse = np.where(inside[:, None], cells // COARSE_CELLS, -1)
        return coarse[:, 0], coarse[:, 1]

    def clearance_bounds_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`clearance_bounds` of each point (N x 2): arrays of lower and upper bounds."""
        i, j = self.coarse_cells_of(xy)
        outside = i < 0
        distance = self._coarse_clearance[np.maximum(i, 0), np.maximum(j, 0)]
        slack = COARSE_CELLS * self.resolution * math.sqrt(2)
        upper = np.where(distance < CLEARANCE_HORIZON_M, distance + slack, math.inf)
        lower = np.maximum(0.0, distance - slack)
        return np.where(outside, 0.0, lower), np.where(outside, 0.0, upper)

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return (int(round((x - self.bounds.x_min) / self.resolution)),
                int(round((y - self.bounds.y_min) / self.resolution)))

    @functools.cached_property
    def _bordered(self) -> np.ndarray:
        """The blocked grid with a blocked border: points outside the map land on it."""
        out = np.ones((self.blocked.shape[0] + 2, self.blocked.shape[1] + 2), dtype=bool)
        out[1:-1, 1:-1] = self.blocked
        return out

    @functools.cached_property
    def _lookup(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(flat bordered grid, offset, lowest and highest cell index) for `blocked_at`."""
        grid = self._bordered
        offset = np.array([self.bounds.x_min, self.bounds.y_min])
        return (grid.ravel(), offset, np.array([-1.0, -1.0]),
                np.array([grid.shape[0] - 2.0, grid.shape[1] - 2.0]))

    def blocked_at(self, xy: np.ndarray) -> np.ndarray:
        """True for points (N x 2) on blocked cells or outside the map."""
        flat, offset, lowest, highest = self._lookup
        idx = np.rint((xy - offset) / self.resolution)
        np.maximum(idx, lowest, out=idx)  # (np.clip's wrapper costs more than the work)
        np.minimum(idx, highest, out=idx)
        cells = idx.astype(np.intp) + 1
        return flat[cells[:, 0] * (self.blocked.shape[1] + 2) + cells[:, 1]]


class _ItemsNear:
    """Where the items standing may meet a group of robot-frame points: the coarse cells
    of the map from which one is within their reach, and, for a pose there, whether one
    (a circle round its box, grown by the margin) meets the points' bounds in the robot's
    frame (most poses near an item hold no point over it: its lookup is saved)."""

    def __init__(self, cells: np.ndarray, boxes: np.ndarray, margin: float,
                 points: np.ndarray):
        self.cells = cells
        self.centres = (boxes[:, :2] + boxes[:, 2:]) / 2
        self.radii = np.hypot(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1]) / 2 + \
            margin
        self.low, self.high = points.min(axis=0), points.max(axis=0)
        # (plain floats for one pose at a time: a handful of items, numpy's calls cost more)
        self._each = list(zip(self.centres[:, 0].tolist(), self.centres[:, 1].tolist(),
                              self.radii.tolist(), strict=True))
        self._bounds = (*self.low.tolist(), *self.high.tolist())

    def meets(self, x: float, y: float, c: float, s: float) -> bool:
        """`meet` of one pose."""
        x0, y0, x1, y1 = self._bounds
        for cx, cy, r in self._each:
            dx, dy = cx - x, cy - y
            fx, fy = c * dx + s * dy, -s * dx + c * dy
            if fx + r >= x0 and fx - r <= x1 and fy + r >= y0 and fy - r <= y1:
                return True
        return False

    def meet(self, xy: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
        """For each pose (N positions, cos and sin of its yaw): may an item meet it?"""
        dx = self.centres[None, :, 0] - xy[:, None, 0]
        dy = self.centres[None, :, 1] - xy[:, None, 1]
        fx = c[:, None] * dx + s[:, None] * dy  # (the centres in the robot's frame)
        fy = -s[:, None] * dx + c[:, None] * dy
        r = self.radii[None, :]
        return np.any((fx + r >= self.low[0]) & (fx - r <= self.high[0]) &
                      (fy + r >= self.low[1]) & (fy - r <= self.high[1]), axis=1)


def _dilated(grid: np.ndarray, radius: int) -> np.ndarray:
    """The grid dilated by a disk of `radius` cells: the grid shifted by every offset in
    the disk, or-ed (a few slices: ndimage's general dilation costs ten times as much on a
    kitchen's map, and a map is drawn for every drawer and door position)."""
    if radius <= 0:
        return grid.copy()
    out = grid.copy()
    nx, ny = grid.shape
    for dx in range(-radius, radius + 1):
        for dy in range(-radius, radius + 1):
            if (dx or dy) and dx * dx + dy * dy <= radius * radius:
                out[max(dx, 0):nx + min(dx, 0), max(dy, 0):ny + min(dy, 0)] |= \
                    grid[max(-dx, 0):nx + min(-dx, 0), max(-dy, 0):ny + min(-dy, 0)]
    return out


def distance_to_nearest(occupied: np.ndarray, horizon: int) -> np.ndarray:
    """Euclidean distance (in cells) from every cell of a boolean grid to the nearest
    occupied cell, exact up to `horizon` cells; farther cells (or all, if none is
    occupied) get `horizon`.

    Separable: the distance along the first axis to the nearest occupied cell of the same
    column, then, along the second, the least of that squared plus the squared column
    offset, over offsets within the horizon. (Written here, not scipy.ndimage's EDT:
    importing scipy.ndimage costs 0.3 s, more than a `cramlite run` has for everything;
    on the 126 x 166 grids of the kitchen this takes ~2 ms.)"""
    nx, ny = occupied.shape
    rows = np.arange(nx)[:, None]
    before = np.maximum.accumulate(np.where(occupied, rows, -horizon - 1), axis=0)
    after = np.minimum.accumulate(np.where(occupied, rows, nx + horizon + 1)[::-1],
                                  axis=0)[::-1]
    along = np.minimum(np.minimum(rows - before, after - rows), horizon + 1).astype(float)
    along *= along
    best = along.copy()
    for offset in range(1, min(horizon, ny - 1) + 1):
        square = float(offset * offset)
        np.minimum(best[:, offset:], along[:, :-offset] + square, out=best[:, offset:])
        np.minimum(best[:, :-offset], along[:, offset:] + square, out=best[:, :-offset])
    return np.minimum(np.sqrt(best), float(horizon))


def convex_hull_2d(points: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of 2-D points, counter-clockwise; fewer than 3
    distinct points, or all on a line: those points.

    Andrew's monotone chain on the points that may be corners: those not strictly inside
    the polygon of the extreme points in eight directions (Akl-Toussaint; mesh outlines
    have thousands of points, a few dozen corners). (Written here: scipy.spatial's import
    costs 0.08 s a process, and qhull wants 3-D or full-dimensional input.)"""
    pts = unique_rows(points)
    if len(pts) < 3:
        return pts
    extreme = pts[sorted(set(np.argmax(pts @ _DIRECTIONS.T, axis=0).tolist()))]
    if len(extreme) >= 3:  # (in the order of the directions: counter-clockwise)
        order = np.argsort(np.arctan2(*(extreme - extreme.mean(axis=0)).T[::-1]))
        ring = extreme[order]
        edges = following(ring) - ring
        rel = pts[:, None, :] - ring[None]
        cross = edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0]
        inside = np.all(cross > 1e-12, axis=1)
        pts = pts[~inside]  # (still sorted by x, then y)
    lower, upper = _chain(pts.tolist()), _chain(pts[::-1].tolist())
    hull = np.array(lower[:-1] + upper[:-1])
    return hull if len(hull) >= 3 else unique_rows(points)


#: The eight directions whose extreme points bound the hull from inside.
_DIRECTIONS = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1],
                        [1, -1]], dtype=float)


def _chain(ordered: list[list[float]]) -> list[list[float]]:
    """One half of the monotone chain: points that turn left (plain floats: a loop)."""
    out: list[list[float]] = []
    for p in ordered:
        while len(out) >= 2:
            o, a = out[-2], out[-1]
            if (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0]) > 0:
                break
            out.pop()
        out.append(p)
    return out


def following(rows: np.ndarray) -> np.ndarray:
    """Each row's successor, the last's the first (`np.roll(rows, -1, axis=0)`, at a
    third of its cost on the few points of an outline)."""
    return np.concatenate((rows[1:], rows[:1]))


def unique_rows(points: np.ndarray) -> np.ndarray:
    """The distinct rows of 2-D points, sorted by x, then y (as `np.unique(..., axis=0)`,
    several times faster on a few hundred points)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(pts) < 2:
        return pts.copy()
    ordered = pts[np.lexsort((pts[:, 1], pts[:, 0]))]
    keep = np.empty(len(ordered), dtype=bool)
    keep[0] = True
    x, y = ordered[:, 0], ordered[:, 1]
    np.logical_or(x[1:] != x[:-1], y[1:] != y[:-1], out=keep[1:])
    return ordered[keep]


def _inside(points: np.ndarray, outline: np.ndarray, slack: float) -> np.ndarray:
    """Which points (... x 2) lie within `slack` of the convex hull of `outline` (N x 2)."""
    hull = convex_hull_2d(outline)
    edges = following(hull) - hull
    normals = np.column_stack([edges[:, 1], -edges[:, 0]])  # outward (counter-clockwise)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    offsets = -np.einsum("ij,ij->i", normals, hull)  # inside: n.x + d <= 0
    return np.all(points @ normals.T + offsets <= slack, axis=-1)


def square_outline(half_size: float, spacing: float) -> np.ndarray:
    """Points along the edge of a square centred at the origin (robot frame)."""
    n = max(2, math.ceil(2 * half_size / spacing) + 1)
    t = np.linspace(-half_size, half_size, n)
    edges = [np.column_stack([t, np.full(n, s)]) for s in (-half_size, half_size)]
    edges += [np.column_stack([np.full(n, s), t]) for s in (-half_size, half_size)]
    return np.vstack(edges)


def square_grid(half_size: float, spacing: float) -> np.ndarray:
    """Points filling a square centred at the origin, `spacing` apart (robot frame)."""
    n = max(2, math.ceil(2 * half_size / spacing) + 1)
    t = np.linspace(-half_size, half_size, n)
    return np.stack(np.meshgrid(t, t), axis=-1).reshape(-1, 2)


class FootprintChecker:
    """Is the robot (square base, and whatever sticks out of it: carried objects, arm
    links) clear of the fixed world at (x, y, yaw)? What sticks out is checked against
    the furniture tall enough to reach it (`set_carried`).
    """

    def __init__(self, occupancy: OccupancyMap, half_size_m: float = PR2_BASE_HALF_SIZE_M,
                 outline_spacing_m: float = 0.04):
        self.occupancy = occupancy
        # the base's edge, then its inside (something small may stand under the base),
        # farthest from the middle first: inside points nearer the middle than the nearest
        # obstacle can be are not looked up (see `_is_free`)
        edge = square_outline(half_size_m, outline_spacing_m)
        inside = square_grid(half_size_m, outline_spacing_m)
        radius = np.hypot(inside[:, 0], inside[:, 1])
        order = np.argsort(-radius, kind="stable")
        self.outline = np.vstack([edge, inside[order]])
        self._inside_radius_ascending = radius[order][::-1].copy()
        self.half_size_m = half_size_m
        #: (robot-frame points, the map they are checked against (the items standing that
        #: they may touch blocked on it too), the coarse cells of that map from which an
        #: obstacle may be within their reach, and the items': see `_ItemsNear`)
        self.carried_groups: list[tuple[np.ndarray, OccupancyMap, np.ndarray,
                                        _ItemsNear | None]] = []
        #: An exact check of what sticks out (robot links, carried objects) at a base pose,
        #: consulted where the 2D outlines say blocked (see `set_carried`).
        self.exact: Callable[[float, float, float], bool] | None = None
        self._known: dict[tuple, bool] = {}
        #: (map id, item boxes) -> (that map, kept alive for its id; it with the boxes)
        self._stamped: dict[tuple, tuple[OccupancyMap, OccupancyMap]] = {}
        self.checks = 0
        pad = occupancy.margin + occupancy.resolution
        self._sure_free = half_size_m * math.sqrt(2) + pad  # circumscribed circle clear
        self._sure_blocked = half_size_m - pad  # something inside the inscribed circle
        # (bounds of the clearance come from a coarse grid: see `clearance_bounds`)

    def set_carried(self, groups: Sequence[tuple], exact: Callable[[float, float, float],
                                                                   bool] | None = None,
                    ) -> None:
        """What sticks out of the base while driving: groups of robot-frame xy points
        outlining a carried object or an arm's link, each with the map of what it can touch
        at its height (None: the full map) and, optionally, the xy boxes [x0, y0, x1, y1]
        (world frame) of the items standing that rise to its height (the maps hold the
        kitchen only: an arm over a counter passes over the counter, not over a box on it).
        Empty when nothing sticks out. `exact(x, y, yaw)`: the precise check to consult
        where an outline touches the furniture or an item's box."""
        pad = self.occupancy.margin + self.occupancy.resolution
        self._known.clear()
        self.exact = exact
        self.carried_groups = []
        # groups checked against the same map are checked together (one lookup a pose)
        by_map: dict[int, tuple[OccupancyMap, list[np.ndarray], np.ndarray]] = {}
        for group in groups:
            points, occupancy = group[0], group[1]
            boxes = np.asarray(group[2] if len(group) > 2 else np.zeros((0, 4)),
                               dtype=float).reshape(-1, 4)
            pts = np.asarray(points, dtype=float).reshape(-1, 2)
            if len(pts):
                occupancy = occupancy or self.occupancy
                entry = by_map.setdefault(id(occupancy), (occupancy, [], boxes))
                entry[1].append(pts)
        for occupancy, parts, boxes in by_map.values():
            pts = np.vstack(parts)
            # (how far they reach from the base's centre, with the margin)
            reach = float(np.hypot(*pts.T).max()) + pad
            near, items = occupancy.near(reach), None  # (near: the kitchen's only)
            if len(boxes):
                items = _ItemsNear(occupancy.near_boxes(boxes, reach + occupancy.margin),
                                   boxes, occupancy.margin, pts)
                occupancy = self._with_boxes(occupancy, boxes)
            self.carried_groups.append((pts, occupancy, near, items))

    def _with_boxes(self, occupancy: OccupancyMap, boxes: np.ndarray) -> OccupancyMap:
        """`occupancy.with_boxes(boxes)`, kept while the items stand where they do (the
        arms move between two updates far more often than an item does)."""
        key = (id(occupancy), boxes.tobytes())
        if key not in self._stamped:
            if len(self._stamped) >= STAMPED_MAPS:
                self._stamped.clear()
            self._stamped[key] = (occupancy, occupancy.with_boxes(boxes))
        return self._stamped[key][1]

    def is_free(self, x: float, y: float, yaw: float) -> bool:
        """Is the robot clear of the world at this base pose? (Answers are remembered
        until what the robot carries changes: location designators ask about the same
        poses again and again.)"""
        x, y, yaw = round(x, 5), round(y, 5), round(yaw, 5)
        key = (id(self.occupancy), x, y, yaw)
        known = self._known.get(key)
        if known is None:
            # (of the pose to 10 um: a base that reaches a goal checked free, up to the
            # last bit of its floats, is free there too, even with a corner on a cell edge)
            known = self._remember(key, self._is_free(x, y, yaw))
        return known

    def _remember(self, key: tuple, free: bool) -> bool:
        """Keep a pose's answer (the memory starts afresh when full); returns it."""
        if len(self._known) > KNOWN_POSES:
            self._known.clear()
        self._known[key] = free
        return free

    def all_free(self, poses: Sequence[tuple[float, float, float]]) -> bool:
        """`all(self.is_free(*p) for p in poses)`, the same answers (and remembered the
        same way), with the poses not known yet checked a chunk at a time, in a few numpy
        steps for the chunk (a path's waypoints: a base check costs ~20 us alone, mostly
        numpy's per-call cost). Poses must be finite (ValueError)."""
        pending: list[tuple[float, float, float]] = []
        for x, y, yaw in poses:
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(yaw)):
                raise ValueError(f"a base pose must be finite, not {(x, y, yaw)}")
            pose = (round(x, 5), round(y, 5), round(yaw, 5))
            key = (id(self.occupancy), *pose)
            if key in self._known:
                # (the poses before it first, as one by one: what is remembered is then as
                # one by one would find it, even where checking them fills the memory)
                if pending and not self._chunks_free(pending):
                    return False
                pending = []
            known = self._known.get(key)
            if known is False:
                return False
            if known is None:
                pending.append(pose)
        return self._chunks_free(pending)

    def _chunks_free(self, poses: list[tuple[float, float, float]]) -> bool:
        for start in range(0, len(poses), BATCH_POSES):
            chunk = poses[start:start + BATCH_POSES]
            answers = self._batch_free(np.array(chunk))
            for pose, free in zip(chunk, answers, strict=True):
                if not self._remember((id(self.occupancy), *pose), free):
                    return False
        return True

    def _batch_free(self, poses: np.ndarray) -> list[bool]:
        """`_is_free` of each pose (N x 3, rounded as `is_free` rounds them), in order, up
        to the first blocked one (the rest: False, not decided; the exact check is not
        consulted for them)."""
        self.checks += len(poses)
        occupancy = self.occupancy
        xy = poses[:, :2]
        yaws = poses[:, 2].tolist()  # (math's cos and sin, as `_is_free`: the same bits)
        c, s = np.array([math.cos(a) for a in yaws]), np.array([math.sin(a) for a in yaws])
        rotation = np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], -2)  # N x 2 x 2
        lower, upper = occupancy.clearance_bounds_of(xy)
        free = upper >= self._sure_blocked
        # the base's outline, where something may be within its reach (less the inside
        # points within the clearance, as `_is_free` skips them: the same lookups)
        pad = occupancy.margin + occupancy.resolution
        check = free & (lower <= self._sure_free)
        if check.any():
            skipped = np.searchsorted(self._inside_radius_ascending, lower[check] - pad,
                                      side="left")
            kept = np.arange(len(self.outline))[None, :] < \
                (len(self.outline) - skipped)[:, None]
            points = self.outline @ rotation[check] + xy[check][:, None, :]
            blocked = occupancy.blocked_at(points.reshape(-1, 2)).reshape(kept.shape)
            free[check] = ~np.any(blocked & kept, axis=1)
        touching = np.zeros(len(poses), dtype=bool)
        for points, group_map, near, items in self.carried_groups:
            i, j = group_map.coarse_cells_of(xy)
            ii, jj = np.maximum(i, 0), np.maximum(j, 0)
            ask = free & ~touching & ((i < 0) | near[ii, jj])
            if items is not None:
                maybe = free & ~touching & ~ask & items.cells[ii, jj]
                if maybe.any():
                    ask[maybe] = items.meet(xy[maybe], c[maybe], s[maybe])
            if ask.any():
                moved = points @ rotation[ask] + xy[ask][:, None, :]
                hit = group_map.blocked_at(moved.reshape(-1, 2)).reshape(moved.shape[:2])
                touching[ask] = hit.any(axis=1)
        out = []
        for pose, ok, touch in zip(poses.tolist(), free.tolist(), touching.tolist(),
                                   strict=True):
            if ok and touch:  # the outlines over-approximate an arm: the exact check decides
                ok = self.exact is not None and self.exact(*pose)
            out.append(ok)
            if not ok:
                return out + [False] * (len(poses) - len(out))
        return out

    def _is_free(self, x: float, y: float, yaw: float) -> bool:
        self.checks += 1
        lower, upper = self.occupancy.clearance_bounds(x, y)
        if upper < self._sure_blocked:
            return False
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, s], [-s, c]])
        # each part is checked only if something it can touch may be within its reach
        if lower <= self._sure_free:
            # (inside points within the clearance, less the margin, are free: skipped)
            pad = self.occupancy.margin + self.occupancy.resolution
            skipped = int(np.searchsorted(self._inside_radius_ascending, lower - pad,
                                          side="left"))
            points = self.outline[:len(self.outline) - skipped]
            if self.occupancy.blocked_at(points @ rotation + (x, y)).any():
                return False
        for points, occupancy, near, items in self.carried_groups:
            # (its own map holds only what rises to its height: mostly far away)
            i, j = occupancy.coarse_cell(x, y)
            if i >= 0 and not near[i, j] and (
                    items is None or not items.cells[i, j] or
                    not items.meets(x, y, c, s)):
                continue
            if occupancy.blocked_at(points @ rotation + (x, y)).any():
                # the outlines over-approximate an arm; the exact check decides, if given
                return self.exact is not None and self.exact(x, y, yaw)
        return True
