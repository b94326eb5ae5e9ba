"""Braking a timed trajectory to rest along its own path (a monitor fired at state k).

From state k on, the robot follows the rest of the path it was on (checked free, so the
braking motion is too) with its path speed falling linearly to zero: the original time
parameter runs as tau(t) = t_k + t - t^2 / (2 T), for t in [0, T], so every velocity is
the original one scaled by 1 - t/T (never faster). T starts at what the deceleration of
the fastest joint (or of the base) needs and grows until the accelerations, by finite
differences of the new states, are within the limits (the same check a trace check
makes). If the rest of the motion is shorter than the braking, the motion is kept: it
ends at rest anyway, within the limits.
"""

from __future__ import annotations

import numpy as np

from cramlite.motion.base_timing import BaseLimits
from cramlite.motion.trajectory import BaseTrajectory, JointLimits, JointTrajectory, wrap_angle

#: Finite differences may exceed a limit by this share (their sampling, as the trace
#: check allows).
BRAKE_TOLERANCE = 0.05


def _braked(positions: np.ndarray, times: np.ndarray, k: int,
            fits: callable) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(new positions, new times, tau of each new state) or None to keep the motion (it
    comes to rest at its own end sooner than braking would).

    The braking states are the motion's own states up to where braking ends, then that
    point: each keeps its place on the path and gets a later time. (States resampled
    every BRAKE_STEP_S between the original ones turned the path's corners within one
    short step: finite differences beyond the limits at any braking time, so a drive
    ran on to its goal after its monitor fired.)"""
    if k >= len(times) - 1:
        return None
    dt0 = max(float(times[k + 1] - times[k]), 1e-9)
    velocity = (positions[k + 1] - positions[k]) / dt0
    duration = fits.first_guess(velocity)
    while True:
        end = times[k] + duration / 2  # (tau at t = duration)
        if end >= times[-1]:
            return None  # (it is at rest sooner along its own profile)
        inner = times[(times > times[k] + 1e-12) & (times < end - 1e-12)]
        tau = np.concatenate([inner, [end]])
        # the time at which tau(t) = t_k + t - t^2 / (2 T) reaches each of them
        t = duration * (1.0 - np.sqrt(np.maximum(0.0, 1.0 - 2.0 * (tau - times[k]) / duration)))
        t = np.maximum(t, np.concatenate([[0.0], t[:-1]]) + 1e-6)  # (strictly later)
        new = np.array([np.interp(tau, times, positions[:, j])
                        for j in range(positions.shape[1])]).T
        out_p = np.vstack([positions[:k + 1], new])
        out_t = np.concatenate([times[:k + 1], times[k] + t])
        if fits(out_p[max(0, k - 1):], out_t[max(0, k - 1):]):
            return out_p, out_t, np.concatenate([times[:k + 1], tau])
        duration *= 1.25


class _JointFit:
    def __init__(self, accel: np.ndarray):
        self.accel = accel

    def first_guess(self, velocity: np.ndarray) -> float:
        return max(float(np.max(np.abs(velocity) / self.accel)) * 1.1, 0.05)

    def __call__(self, p: np.ndarray, t: np.ndarray) -> bool:
        return bool(np.all(_fd_accel(p, t) <= self.accel * (1 + BRAKE_TOLERANCE) + 1e-9))


class _BaseFit:
    def __init__(self, limits: BaseLimits):
        self.limits = limits

    def first_guess(self, velocity: np.ndarray) -> float:
        return max(float(np.hypot(velocity[0], velocity[1])) / self.limits.accel_m_s2,
                   abs(float(velocity[2])) / self.limits.turn_accel_rad_s2) * 1.1 + 0.05

    def __call__(self, p: np.ndarray, t: np.ndarray) -> bool:
        a = _fd_accel_vectors(p, t)
        tol = 1 + BRAKE_TOLERANCE
        return bool(np.all(np.hypot(a[:, 0], a[:, 1]) <= self.limits.accel_m_s2 * tol + 1e-9)
                    and np.all(np.abs(a[:, 2]) <= self.limits.turn_accel_rad_s2 * tol + 1e-9))


def _fd_accel_vectors(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Accelerations by finite differences, to rest after the last state."""
    if len(p) < 2:
        return np.zeros((1, p.shape[1]))
    dt = np.maximum(np.diff(t), 1e-9)
    v = np.diff(p, axis=0) / dt[:, None]
    v = np.vstack([v, np.zeros((1, p.shape[1]))])
    # (to rest over half the last step: between its middle and its end, as the trace
    # check counts it; over the whole step, braking passed twice what the check allows)
    gap = np.concatenate([(dt[:-1] + dt[1:]) / 2, [dt[-1] / 2]])
    return np.diff(v, axis=0) / gap[:, None]


def _fd_accel(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    return np.abs(_fd_accel_vectors(p, t))


def brake_joint_trajectory(trajectory: JointTrajectory, k: int,
                           limits: JointLimits) -> JointTrajectory:
    """The trajectory to state k, then braking to rest along its path (see the module)."""
    accel = np.array([limits.acceleration[n] for n in trajectory.names])
    result = _braked(np.asarray(trajectory.positions, dtype=float),
                     np.asarray(trajectory.times, dtype=float), k, _JointFit(accel))
    if result is None:
        return trajectory
    positions, times, tau = result
    world = {joint: np.interp(tau, trajectory.times, values)
             for joint, values in trajectory.world.items()}
    return JointTrajectory(trajectory.names, positions, times, world)


def brake_base_trajectory(trajectory: BaseTrajectory, k: int,
                          limits: BaseLimits) -> BaseTrajectory:
    """The base trajectory to state k, then braking to rest along its path."""
    poses = np.asarray(trajectory.poses, dtype=float).copy()
    poses[:, 2] = np.unwrap(poses[:, 2])
    result = _braked(poses, np.asarray(trajectory.times, dtype=float), k, _BaseFit(limits))
    if result is None:
        return trajectory
    positions, times, _ = result
    positions[:, 2] = wrap_angle(positions[:, 2])
    return BaseTrajectory(positions, times)
