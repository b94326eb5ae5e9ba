"""Timing a base path with finite acceleration: corners blended, then a time-optimal speed
profile along the path.

A planned base path is a polyline in (x, y, yaw) (the PR2's base is holonomic: it drives
and turns at once). Driven as it is, every vertex is a stop (a corner taken at speed needs
an infinite acceleration). So each corner that is not a cusp (the direction turning by
more than `CUSP_DEG`, a reversal) is replaced by a blend: a quadratic Bezier curve from a
point before the vertex to one after it, inside the corner's triangle, checked state by
state with the same footprint check as the path (shortened, and at last dropped, where it
is not free). The robot drives through a blend at the constant speed its curvature allows
(sideways acceleration, yaw acceleration and the speed limits), and along each straight
stretch between blends with the fastest trapezoid between the blends' speeds: the forward
and backward passes of a junction-speed planner (as CNC motion planners do), which is
time-optimal along straight stretches. It stops at cusps, at turns on the spot and at
the goal.

Written here rather than with TOPP-RA (`toppra`): that package needs matplotlib and costs
0.6 s to import (scipy.interpolate), more than a whole `cramlite run` may take; and
Ruckig's community version cannot pass intermediate waypoints with non-zero speed on a
given path. A test compares the result with a time-optimal retiming of the same path.

Limits (`BaseLimits`): 1 m/s and 1 rad/s (the source's PR2 speed); 1 m/s^2 and 1.5 rad/s^2
are an assumption, gentler than the PR2's navigation defaults (move_base's local planner
as configured for the PR2 allowed 2.5 m/s^2 and 3.2 rad/s^2), for a robot that carries
open cups.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.motion.trajectory import MAX_BASE_STEP_M, MAX_BASE_TURN_RAD, wrap_angle

#: A turn of the path's direction by more than this is a cusp: the base stops there.
CUSP_DEG = 120.0
#: A blend reaches at most this far from its vertex, and at most this share of each
#: neighbouring segment (so blends never overlap).
BLEND_MAX_M = 0.5
BLEND_SHARE = 0.45
#: Times a blend that is not free is halved before the corner is taken with a stop.
BLEND_RETRIES = 4
#: Rounds of lowering speeds where measured accelerations exceed the limits by more than
#: FIT_TOLERANCE (a share of the limit).
FIT_PASSES = 6
FIT_TOLERANCE = 1.01

PoseCheck = Callable[[float, float, float], bool]


@dataclass(frozen=True)
class BaseLimits:
    """Speed and acceleration limits of the base (see the module's doc for the source)."""

    speed_m_s: float = 1.0
    turn_rad_s: float = 1.0
    accel_m_s2: float = 1.0
    turn_accel_rad_s2: float = 1.5

    @property
    def yaw_scale_m(self) -> float:
        """Metres a radian of yaw counts as in the path's arc length (speed / turn rate)."""
        return self.speed_m_s / self.turn_rad_s


@dataclass(frozen=True)
class TimedBasePath:
    """Dense base poses (x, y, yaw in [-pi, pi)) and the time of each."""

    poses: np.ndarray
    times: np.ndarray
    #: Indices (among the polyline's inner vertices) of the corners taken with a stop.
    stops: tuple[int, ...] = ()


def corners(poses: np.ndarray, scale: float) -> np.ndarray:
    """The vertices of the polyline that dense, collinear-stepped poses lie on (first,
    last, and every pose where the direction changes), in the scaled space (x, y, scale *
    unwrapped yaw)."""
    z = _scaled(poses, scale)
    if len(z) < 2:
        return z
    steps = np.diff(z, axis=0)
    lengths = np.linalg.norm(steps, axis=1)
    keep = lengths > 1e-12
    z = np.vstack([z[0], z[1:][keep]])
    steps = steps[keep]
    if len(steps) < 2:
        return z
    unit = steps / np.linalg.norm(steps, axis=1)[:, None]
    turn = np.linalg.norm(np.diff(unit, axis=0), axis=1) > 1e-6
    inner = np.flatnonzero(turn) + 1
    return np.vstack([z[0], z[inner], z[-1]])


def _scaled(poses: np.ndarray, scale: float) -> np.ndarray:
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    yaw = np.unwrap(poses[:, 2])
    return np.column_stack([poses[:, 0], poses[:, 1], scale * yaw])


def time_base_path(waypoints: Sequence[Sequence[float]], limits: BaseLimits | None = None,
                   is_free: PoseCheck | None = None) -> TimedBasePath:
    """Blend the corners of the path through `waypoints` (x, y, yaw; dense or not), check
    each blend with `is_free` (None: no blends, a stop at every vertex), densify and time
    it under the limits."""
    limits = limits or BaseLimits()
    scale = limits.yaw_scale_m
    vertices = corners(np.asarray(waypoints, dtype=float), scale)
    if len(vertices) < 2:
        pose = _unscaled(vertices[:1], scale)
        return TimedBasePath(pose, np.zeros(len(pose)))
    pieces, stops = _pieces(vertices, limits, is_free)
    return _timed(pieces, limits, stops)


@dataclass
class _Piece:
    """A straight stretch (`curve` None) or a blend (`curve`: dense points, scaled space)."""

    start: np.ndarray
    end: np.ndarray
    curve: np.ndarray | None = None


def _pieces(vertices: np.ndarray, limits: BaseLimits,
            is_free: PoseCheck | None) -> tuple[list[_Piece], tuple[int, ...]]:
    """Straight stretches and blends, alternating (a blend of length 0 is a stop)."""
    scale = limits.yaw_scale_m
    edges = np.diff(vertices, axis=0)
    lengths = np.linalg.norm(edges, axis=1)
    units = edges / lengths[:, None]
    blends: list[_Piece] = []
    stops = []
    for j in range(1, len(vertices) - 1):
        vertex, u_in, u_out = vertices[j], units[j - 1], units[j]
        blend = None
        # (a blend needs both neighbours to move the base: a turn on the spot stops)
        moving = np.linalg.norm(u_in[:2]) > 1e-6 and np.linalg.norm(u_out[:2]) > 1e-6
        if moving and float(u_in @ u_out) > math.cos(math.radians(CUSP_DEG)) \
                and is_free is not None:
            reach = min(BLEND_MAX_M, BLEND_SHARE * lengths[j - 1], BLEND_SHARE * lengths[j])
            for _ in range(BLEND_RETRIES + 1):
                curve = _bezier(vertex - reach * u_in, vertex, vertex + reach * u_out, scale)
                poses = _unscaled(curve, scale)
                if all(is_free(float(x), float(y), float(yaw)) for x, y, yaw in poses):
                    blend = _Piece(curve[0], curve[-1], curve)
                    break
                reach /= 2
        if blend is None:
            stops.append(j - 1)
            blend = _Piece(vertex, vertex)
        blends.append(blend)
    pieces = []
    start = vertices[0]
    for blend in blends:
        pieces += [_Piece(start, blend.start), blend]
        start = blend.end
    pieces.append(_Piece(start, vertices[-1]))
    return pieces, tuple(stops)


def _bezier(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, scale: float) -> np.ndarray:
    """Points along the quadratic Bezier curve p0 -> p2 (control point p1), closer than the
    largest base steps."""
    chord = float(np.linalg.norm(p1 - p0) + np.linalg.norm(p2 - p1))
    turn = float(max(abs(p1[2] - p0[2]), abs(p2[2] - p1[2])) * 2 / scale)
    n = max(2, math.ceil(max(chord / MAX_BASE_STEP_M, turn / MAX_BASE_TURN_RAD)) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) ** 2 * p0 + 2 * (1 - t) * t * p1 + t ** 2 * p2


def _limits_at(q1: Sequence[float], q2: Sequence[float], b: float, limits: BaseLimits,
               scale: float) -> tuple[float, float]:
    """The path accelerations s'' allowed at a point with tangent q1 and curvature q2
    (scaled space) moving at s'^2 = b: |q1_xy s'' + q2_xy b| within the acceleration limit
    (a norm), |q1_yaw s'' + q2_yaw b| within the yaw acceleration limit. Empty: (1, -1).
    (Plain floats: called for every point of every pass.)"""
    lo, hi = -math.inf, math.inf
    cx, cy, dx, dy = q1[0], q1[1], q2[0] * b, q2[1] * b
    cc, cd = cx * cx + cy * cy, cx * dx + cy * dy
    dd = dx * dx + dy * dy - limits.accel_m_s2 ** 2
    if cc > 1e-12:
        disc = cd * cd - cc * dd
        if disc < 0:
            return 1.0, -1.0
        root = math.sqrt(disc)
        lo, hi = (-cd - root) / cc, (-cd + root) / cc
    elif dd > 0:
        return 1.0, -1.0
    c3, d3 = q1[2] / scale, q2[2] * b / scale
    if abs(c3) > 1e-12:
        a1 = (-limits.turn_accel_rad_s2 - d3) / c3
        a2 = (limits.turn_accel_rad_s2 - d3) / c3
        lo, hi = max(lo, min(a1, a2)), min(hi, max(a1, a2))
    elif abs(d3) > limits.turn_accel_rad_s2:
        return 1.0, -1.0
    return lo, hi


def _speed_cap(q1: Sequence[float], q2: Sequence[float], limits: BaseLimits,
               scale: float) -> float:
    """The largest s'^2 at a point: the speed limits, and the curvature's acceleration
    within the limits (at s'' = 0)."""
    cap = math.inf
    xy, yaw = math.hypot(q1[0], q1[1]), abs(q1[2]) / scale
    if xy > 1e-12:
        cap = min(cap, (limits.speed_m_s / xy) ** 2)
    if yaw > 1e-12:
        cap = min(cap, (limits.turn_rad_s / yaw) ** 2)
    bend_xy, bend_yaw = math.hypot(q2[0], q2[1]), abs(q2[2]) / scale
    if bend_xy > 1e-12:
        cap = min(cap, limits.accel_m_s2 / bend_xy)
    if bend_yaw > 1e-12:
        cap = min(cap, limits.turn_accel_rad_s2 / bend_yaw)
    return cap


def _dense(pieces: list[_Piece], scale: float,
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """The path's points (scaled space), the tangent and curvature at each, and the
    indices of the points where the base must stand still (the ends, stops)."""
    points, rests = [pieces[0].start], [0]
    for k, piece in enumerate(pieces):
        if k % 2 and piece.curve is None:  # a corner taken with a stop
            rests.append(len(points) - 1)
            continue
        if piece.curve is None:
            delta = piece.end - piece.start
            length = float(np.linalg.norm(delta))
            if length <= 1e-12:
                continue
            steps = max(1, math.ceil(max(float(np.hypot(delta[0], delta[1])) / MAX_BASE_STEP_M,
                                         abs(float(delta[2])) / scale / MAX_BASE_TURN_RAD)
                                     - 1e-9))
            t = np.arange(1, steps + 1)[:, None] / steps
            points.extend(piece.start + t * delta)
            continue
        points.extend(piece.curve[1:])
    z = np.array(points)
    n = len(z)
    q1, q2 = np.zeros((n, 3)), np.zeros((n, 3))
    if n < 2:
        return z, q1, q2, [0]
    # tangents and curvature by differences along the dense points (exact on straight
    # stretches; on the blends as close as their sampling)
    step = np.diff(z, axis=0)
    ds = np.linalg.norm(step, axis=1)
    unit = step / np.maximum(ds, 1e-12)[:, None]
    q1[:-1], q1[-1] = unit, unit[-1]
    q1[1:-1] = unit[:-1] + unit[1:]
    q1[1:-1] /= np.maximum(np.linalg.norm(q1[1:-1], axis=1), 1e-12)[:, None]
    q2[1:-1] = (unit[1:] - unit[:-1]) / ((ds[1:] + ds[:-1]) / 2)[:, None]
    rests.append(n - 1)
    for r in rests:  # (a stop's corner has no curvature to speak of: it is stood still on)
        q2[r] = 0.0
    return z, q1, q2, sorted(set(rests))


def _timed(pieces: list[_Piece], limits: BaseLimits, stops: tuple[int, ...]) -> TimedBasePath:
    """Times along the dense path: each point's speed at most what its speed limits and
    curvature allow, then the backward pass (able to slow down for every later point) and
    the forward pass (speeding up as the limits allow), with constant path acceleration
    between points."""
    scale = limits.yaw_scale_m
    z, tangents, bends, rests = _dense(pieces, scale)
    n = len(z)
    if n < 2:  # (every piece of no length: it stands where it is)
        pose = _unscaled(z, scale)
        return TimedBasePath(pose, np.zeros(len(pose)))
    ds = np.linalg.norm(np.diff(z, axis=0), axis=1).tolist()
    q1, q2 = tangents.tolist(), bends.tolist()
    cap = [_speed_cap(q1[i], q2[i], limits, scale) for i in range(n)]
    for r in rests:
        cap[r] = 0.0
    # the limits hold for the continuous path; measured as a trace check does (finite
    # differences of the states' velocities) a tight blend can exceed them by a few per
    # cent: where it does, that point's speed is lowered and the passes are run again
    for _ in range(FIT_PASSES):
        times = _passes(cap, ds, q1, q2, limits, scale)
        excess = _measured_excess(z, times, limits, scale)
        if excess.max() <= FIT_TOLERANCE:
            break
        over = np.flatnonzero(excess > FIT_TOLERANCE)
        speeds_sq = _squared_speeds(ds, times)
        for i in over:
            for j in (i - 1, i):  # (the steps either side of the point)
                if 0 <= j < n - 1:
                    lowered = speeds_sq[j] / (excess[i] * 1.02)
                    cap[j] = min(cap[j], lowered)
                    cap[j + 1] = min(cap[j + 1], lowered)
    return TimedBasePath(_unscaled(z, scale), times, stops)


def _passes(cap: list[float], ds: list[float], q1: list[list[float]],
            q2: list[list[float]], limits: BaseLimits, scale: float) -> np.ndarray:
    """The times of the points after the backward and forward passes under `cap`."""
    n = len(cap)
    b = list(cap)
    for i in range(n - 2, -1, -1):  # backward: from b[i], slowing down reaches b[i + 1]
        if b[i] <= b[i + 1]:
            continue
        b[i] = min(b[i], _largest_start(b[i + 1], ds[i], q1[i], q2[i], limits, scale))
    for i in range(n - 1):  # forward: speeding up from b[i] as the limits allow
        _, hi = _limits_at(q1[i], q2[i], b[i], limits, scale)
        b[i + 1] = min(b[i + 1], max(0.0, b[i] + 2 * max(hi, 0.0) * ds[i]))
    speed = np.sqrt(np.maximum(b, 0.0))
    ds_arr = np.asarray(ds)
    # a step between two points at rest (a stop right after a stop): speed up over its
    # first half, slow down over the second (the constant-acceleration time is infinite)
    accel = np.array([limits_decel(limits, q, scale) for q in q1[:-1]])
    rest_to_rest = 2 * np.sqrt(ds_arr / np.maximum(accel, 1e-12))
    moving = speed[:-1] + speed[1:]
    dt = np.where(moving > 1e-9, 2 * ds_arr / np.maximum(moving, 1e-12), rest_to_rest)
    dt = np.minimum(dt, rest_to_rest)
    return np.concatenate([[0.0], np.cumsum(dt)])


def _squared_speeds(ds: list[float], times: np.ndarray) -> np.ndarray:
    """Each step's mean path speed, squared."""
    return (np.asarray(ds) / np.maximum(np.diff(times), 1e-12)) ** 2


def _measured_excess(z: np.ndarray, times: np.ndarray, limits: BaseLimits,
                     scale: float) -> np.ndarray:
    """At each point, the finite-difference acceleration (xy norm, yaw) over its limit
    (the base at rest before the first point and after the last)."""
    dt = np.maximum(np.diff(times), 1e-12)
    v = np.diff(z, axis=0) / dt[:, None]
    v = np.vstack([np.zeros(3), v, np.zeros(3)])
    half = np.concatenate([[0.0], dt, [0.0]])
    a = np.diff(v, axis=0) / np.maximum((half[:-1] + half[1:]) / 2, 1e-12)[:, None]
    return np.maximum(np.hypot(a[:, 0], a[:, 1]) / limits.accel_m_s2,
                      np.abs(a[:, 2]) / scale / limits.turn_accel_rad_s2)


def _largest_start(b_next: float, ds: float, q1: Sequence[float], q2: Sequence[float],
                   limits: BaseLimits, scale: float) -> float:
    """The largest b at a point from which braking over `ds` reaches b_next (bisection:
    the braking allowed shrinks as the speed grows on a curve)."""
    def reaches(b: float) -> bool:
        lo, hi = _limits_at(q1, q2, b, limits, scale)
        return lo <= hi and b + 2 * lo * ds <= b_next + 1e-12
    low, high = b_next, b_next + 2 * limits_decel(limits, q1, scale) * ds
    if not any(q2) or reaches(high):  # (on a straight stretch braking is the same at
        # every speed)
        return high
    for _ in range(30):
        mid = (low + high) / 2
        low, high = (mid, high) if reaches(mid) else (low, mid)
    return low


def limits_decel(limits: BaseLimits, q1: Sequence[float], scale: float) -> float:
    """The largest path deceleration along tangent q1 on a straight line."""
    xy, yaw = math.hypot(q1[0], q1[1]), abs(q1[2]) / scale
    return min(limits.accel_m_s2 / xy if xy > 1e-12 else math.inf,
               limits.turn_accel_rad_s2 / yaw if yaw > 1e-12 else math.inf)


def _unscaled(z: np.ndarray, scale: float) -> np.ndarray:
    z = np.atleast_2d(z)
    yaw = wrap_angle(z[:, 2] / scale)
    return np.column_stack([z[:, 0], z[:, 1], yaw])
