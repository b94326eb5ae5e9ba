"""Base trajectories with finite acceleration: measured by finite differences of the timed
states (as a trace check would), compared with an independent time-optimal retiming of
the same path (a discretised TOPP, written here), stopping only at cusps and goals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cramlite.motion.base_timing import BaseLimits, time_base_path

LIMITS = BaseLimits()
#: A path with an ordinary corner (90 degrees, turning while driving), a cusp (reversing
#: at 160 degrees) and a turn on the spot at the end.
PATH = [(0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (2.0, 1.5, 1.2), (0.5, 1.0, 1.2),
        (1.8, 1.3, 1.2), (1.8, 1.3, -2.5)]


def finite_differences(poses: np.ndarray, times: np.ndarray):
    """Speeds (per step) and accelerations (between steps) in xy and yaw."""
    p = poses.copy()
    p[:, 2] = np.unwrap(p[:, 2])
    dt = np.diff(times)
    keep = dt > 1e-9
    v = np.diff(p, axis=0)[keep] / dt[keep, None]
    mid = ((times[1:] + times[:-1]) / 2)[keep]
    # from rest before and to rest after
    v = np.vstack([np.zeros(3), v, np.zeros(3)])
    mid = np.concatenate([[times[0]], mid, [times[-1]]])
    a = np.diff(v, axis=0) / np.maximum(np.diff(mid), 1e-9)[:, None]
    return v, a


def reference_time(poses: np.ndarray, limits: BaseLimits) -> float:
    """The least time along the same states: b = s'^2 at each state, s'' on each step, the
    speed and acceleration limits at each state (xy as a norm, yaw alone), at rest at both
    ends; TOPP-RA's backward pass (largest controllable b, by bisection) and greedy forward
    pass."""
    r = limits.yaw_scale_m
    z = np.column_stack([poses[:, 0], poses[:, 1], r * np.unwrap(poses[:, 2])])
    ds = np.linalg.norm(np.diff(z, axis=0), axis=1)
    keep = np.concatenate([[True], ds > 1e-12])
    z = z[keep]
    ds = np.linalg.norm(np.diff(z, axis=0), axis=1)
    n = len(z)
    d1 = np.zeros((n, 3))
    d2 = np.zeros((n, 3))
    for i in range(n):
        lo, hi = max(i - 1, 0), min(i + 1, n - 1)
        d1[i] = (z[hi] - z[lo]) / np.linalg.norm(z[hi] - z[lo])
        if 0 < i < n - 1:
            d2[i] = ((z[i + 1] - z[i]) / ds[i] - (z[i] - z[i - 1]) / ds[i - 1]) / \
                ((ds[i] + ds[i - 1]) / 2)

    def speed_bound(i: int) -> float:
        xy, yaw = np.hypot(*d1[i, :2]), abs(d1[i, 2]) / r
        out = math.inf
        if xy > 1e-12:
            out = min(out, (limits.speed_m_s / xy) ** 2)
        if yaw > 1e-12:
            out = min(out, (limits.turn_rad_s / yaw) ** 2)
        return out

    def accel_range(i: int, b: float) -> tuple[float, float]:
        lo, hi = -math.inf, math.inf
        c, d = d1[i, :2], d2[i, :2] * b  # |c a + d| <= A
        cc, cd, dd = c @ c, c @ d, d @ d - limits.accel_m_s2 ** 2
        if cc > 1e-12:
            disc = cd * cd - cc * dd
            if disc < 0:
                return 1.0, -1.0
            root = math.sqrt(disc)
            lo, hi = max(lo, (-cd - root) / cc), min(hi, (-cd + root) / cc)
        elif dd > 0:
            return 1.0, -1.0
        c3, d3 = d1[i, 2] / r, d2[i, 2] * b / r  # |c3 a + d3| <= alpha
        if abs(c3) > 1e-12:
            a1 = (-limits.turn_accel_rad_s2 - d3) / c3
            a2 = (limits.turn_accel_rad_s2 - d3) / c3
            lo, hi = max(lo, min(a1, a2)), min(hi, max(a1, a2))
        elif abs(d3) > limits.turn_accel_rad_s2:
            return 1.0, -1.0
        return lo, hi

    top = np.zeros(n)  # the largest b from which the end can still be reached at rest
    for i in range(n - 2, -1, -1):
        def reachable(b: float, i: int = i) -> bool:
            lo, hi = accel_range(i, b)
            lo, hi = max(lo, -b / (2 * ds[i])), min(hi, (top[i + 1] - b) / (2 * ds[i]))
            return lo <= hi
        cap = min(speed_bound(i), 100.0)
        if i == 0:
            cap = 0.0
        low, high = 0.0, cap
        if reachable(high):
            low = high
        else:
            for _ in range(50):
                mid = (low + high) / 2
                low, high = (mid, high) if reachable(mid) else (low, mid)
        top[i] = low
    b = np.zeros(n)
    for i in range(n - 1):
        lo, hi = accel_range(i, b[i])
        b[i + 1] = min(top[i + 1], max(0.0, b[i] + 2 * hi * ds[i]))
    speed = np.sqrt(b)
    return float(np.sum(2 * ds / np.maximum(speed[:-1] + speed[1:], 1e-12)))


def test_accelerations_stay_within_the_limits_and_the_base_stops_only_at_cusps() -> None:
    timed = time_base_path(PATH, LIMITS, is_free=lambda x, y, yaw: True)
    v, a = finite_differences(timed.poses, timed.times)
    print("peaks", np.hypot(v[:, 0], v[:, 1]).max(), np.abs(v[:, 2]).max(),
          np.hypot(a[:, 0], a[:, 1]).max(), np.abs(a[:, 2]).max())
    assert np.hypot(v[:, 0], v[:, 1]).max() <= LIMITS.speed_m_s * 1.001
    assert np.abs(v[:, 2]).max() <= LIMITS.turn_rad_s * 1.001
    assert np.hypot(a[:, 0], a[:, 1]).max() <= LIMITS.accel_m_s2 * 1.02
    assert np.abs(a[:, 2]).max() <= LIMITS.turn_accel_rad_s2 * 1.02
    assert timed.stops == (2, 3)  # the cusp at (0.5, 1.0), the turn on the spot
    speed = np.hypot(v[1:-1, 0], v[1:-1, 1])
    near = np.linalg.norm(timed.poses[:-1, :2] - np.array([2.0, 0.0]), axis=1)
    assert speed[np.argmin(near)] > 0.3  # the 90-degree corner is driven through


def test_drive_time_is_within_five_percent_of_a_time_optimal_retiming() -> None:
    timed = time_base_path(PATH, LIMITS, is_free=lambda x, y, yaw: True)
    best = reference_time(timed.poses, LIMITS)
    print("timed", timed.times[-1], "time-optimal", best)
    assert best <= timed.times[-1] <= 1.05 * best


def test_a_blend_that_is_not_free_becomes_a_stop() -> None:
    def near_corner(x: float, y: float, yaw: float) -> bool:
        """Only the polyline itself is free near the corner at (2, 0)."""
        return math.dist((x, y), (2.0, 0.0)) > 0.6 or abs(x - 2.0) < 1e-9 or abs(y) < 1e-9


    timed = time_base_path(PATH[:3], LIMITS, is_free=near_corner)
    assert timed.stops == (0,)
    free = time_base_path(PATH[:3], LIMITS, is_free=lambda x, y, yaw: True)
    assert free.stops == () and free.times[-1] < timed.times[-1]
    v, _ = finite_differences(timed.poses, timed.times)
    at = np.argmin(np.linalg.norm(timed.poses[:, :2] - np.array([2.0, 0.0]), axis=1))
    assert np.hypot(*v[at, :2]) < 0.15 and np.hypot(*v[at + 1, :2]) < 0.15  # stopped there


@pytest.mark.parametrize("limits", [BaseLimits(accel_m_s2=0.5), BaseLimits(speed_m_s=0.5)])
def test_other_limits_are_kept(limits: BaseLimits) -> None:
    timed = time_base_path(PATH, limits, is_free=lambda x, y, yaw: True)
    v, a = finite_differences(timed.poses, timed.times)
    assert np.hypot(v[:, 0], v[:, 1]).max() <= limits.speed_m_s * 1.001
    assert np.hypot(a[:, 0], a[:, 1]).max() <= limits.accel_m_s2 * 1.02
