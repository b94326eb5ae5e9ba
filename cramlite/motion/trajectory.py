"""Timed trajectories: dense joint-space and base paths with a time for every state.

A path is a polyline: straight segments between vertices. It is densified so that
straight interpolation between consecutive states is what the robot does (at most
`MAX_JOINT_STEP_RAD` per revolute joint, `MAX_PRISMATIC_STEP_M` per prismatic joint;
`MAX_BASE_STEP_M` / `MAX_BASE_TURN_RAD` for the base), and timed:

- joints: each segment is a rest-to-rest motion computed by Ruckig with phase
  synchronisation, under the URDF's velocity limits and an acceleration limit per joint.
  Phase synchronisation makes every joint follow the same normalised profile, so the
  timed motion stays exactly on the straight segment that was collision-checked (a
  spline-based parameteriser such as TOPP-RA would round the corners between checked
  segments). The time of each dense state is where the leading joint reaches it.
- base: see `cramlite.motion.base_timing` (corners blended, finite acceleration).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory

#: Largest change of a revolute joint between consecutive states (radians).
MAX_JOINT_STEP_RAD = 0.05
#: Largest change of a prismatic joint (the torso) between consecutive states (metres).
MAX_PRISMATIC_STEP_M = 0.01
#: Largest base translation / rotation between consecutive states.
MAX_BASE_STEP_M = 0.02
MAX_BASE_TURN_RAD = 0.05
#: The URDF gives velocity limits only: a joint reaches its top speed in this time.
ACCELERATION_TIME_S = 0.25


def wrap_angle(a: float | np.ndarray) -> float | np.ndarray:
    """Into [-pi, pi) (each of an array's angles, elementwise)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of a robot, by joint name (from its URDF)."""

    lower: Mapping[str, float]
    upper: Mapping[str, float]
    velocity: Mapping[str, float]
    acceleration: Mapping[str, float]
    continuous: frozenset[str]
    prismatic: frozenset[str]

    def max_steps(self, names: Sequence[str]) -> np.ndarray:
        """Largest change per joint between consecutive states."""
        return np.array([MAX_PRISMATIC_STEP_M if n in self.prismatic else MAX_JOINT_STEP_RAD
                         for n in names])

    def unwrap_goal(self, names: Sequence[str], start: np.ndarray, goal: np.ndarray,
                    ) -> np.ndarray:
        """The goal with each continuous joint moved to its nearest equivalent angle, so a
        straight line turns it the short way."""
        out = np.array(goal, dtype=float)
        for i, name in enumerate(names):
            if name in self.continuous:
                out[i] = start[i] + wrap_angle(goal[i] - start[i])
        return out


@dataclass(frozen=True)
class JointTrajectory:
    """Joint positions (states x joints) and the robot time of each state (from 0);
    `world`: values of world joints (a drawer, a door) that move along with the robot's,
    one per state (the robot pulls the handle; a simulation moves the joint with it)."""

    names: tuple[str, ...]
    positions: np.ndarray
    times: np.ndarray
    world: dict[str, np.ndarray] = field(default_factory=dict)
    #: Positions at any robot times (from 0 to the end) on the timed motion itself, where
    #: the timing knows it (`time_joint_path`: each segment's Ruckig profile). Sampled more
    #: finely than its states (while the base drives), a motion interpolated straight
    #: between them would change speed in a jump at every state.
    profile: Callable[[np.ndarray], np.ndarray] | None = field(default=None, compare=False,
                                                               repr=False)

    @property
    def duration_s(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

    def at_times(self, times: np.ndarray) -> np.ndarray:
        """Positions (len(times) x joints) at these robot times: on the profile where it is
        known, else straight between the states (each held before the first and after the
        last)."""
        times = np.asarray(times, dtype=float)
        if self.profile is not None:
            return self.profile(times)
        return np.column_stack([np.interp(times, self.times, self.positions[:, k])
                                for k in range(self.positions.shape[1])])

    def final(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.positions[-1], strict=True)}

    def __len__(self) -> int:
        return len(self.times)


@dataclass(frozen=True)
class BaseTrajectory:
    """Base poses (states x [x, y, yaw]) and the robot time of each state (from 0)."""

    poses: np.ndarray
    times: np.ndarray

    @property
    def duration_s(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

    @property
    def length_m(self) -> float:
        if len(self.poses) < 2:
            return 0.0
        return float(np.hypot(*np.diff(self.poses[:, :2], axis=0).T).sum())

    def __len__(self) -> int:
        return len(self.times)


def densify(vertices: np.ndarray, max_steps: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """States along the polyline through `vertices` (k x n), at most `max_steps` apart per
    joint; returns them and the index of each vertex among them."""
    vertices = np.atleast_2d(np.asarray(vertices, dtype=float))
    out = [vertices[0]]
    at = [0]
    for a, b in zip(vertices[:-1], vertices[1:], strict=True):
        steps = max(1, math.ceil(float(np.max(np.abs(b - a) / max_steps)) - 1e-9))
        t = np.arange(1, steps + 1)[:, None] / steps
        out.extend(a + t * (b - a))
        at.append(len(out) - 1)
    return np.array(out), at


def segment_profile(start: np.ndarray, goal: np.ndarray, velocity: np.ndarray,
                    acceleration: np.ndarray):
    """A rest-to-rest, phase-synchronised Ruckig trajectory from start to goal."""
    n = len(start)
    otg = Ruckig(n)
    inp = InputParameter(n)
    inp.current_position = [float(v) for v in start]
    inp.target_position = [float(v) for v in goal]
    inp.max_velocity = [float(v) for v in velocity]
    inp.max_acceleration = [float(v) for v in acceleration]
    inp.max_jerk = [math.inf] * n
    inp.synchronization = Synchronization.Phase
    trajectory = Trajectory(n)
    result = otg.calculate(inp, trajectory)
    if result not in (Result.Working, Result.Finished):
        raise ValueError(f"Ruckig could not time the segment ({result})")
    return trajectory


def time_joint_path(names: Sequence[str], vertices: np.ndarray, limits: JointLimits,
                    ) -> JointTrajectory:
    """Densify and time a joint-space polyline (vertices k x n, continuous joints already
    unwrapped); the robot rests at every vertex."""
    names = tuple(names)
    vertices = np.atleast_2d(np.asarray(vertices, dtype=float))
    steps = limits.max_steps(names)
    velocity = np.array([limits.velocity[n] for n in names])
    acceleration = np.array([limits.acceleration[n] for n in names])
    positions, times = [vertices[0]], [0.0]
    t0 = 0.0
    segments = []  # (start time, profile, end vertex)
    for a, b in zip(vertices[:-1], vertices[1:], strict=True):
        delta = b - a
        if not np.any(np.abs(delta) > 1e-12):
            continue
        dense, _ = densify(np.vstack([a, b]), steps)
        profile = segment_profile(a, b, velocity, acceleration)
        lead = int(np.argmax(np.abs(delta) / velocity))  # the joint that sets the pace
        for state in dense[1:-1]:
            at = profile.get_first_time_at_position(lead, float(state[lead]))
            positions.append(state)
            times.append(t0 + (float(at) if at is not None else 0.0))
        segments.append((t0, profile, b))
        t0 += float(profile.duration)
        positions.append(b)
        times.append(t0)
    times_arr = np.maximum.accumulate(np.array(times))  # guard against rounding
    return JointTrajectory(names, np.array(positions), times_arr,
                           profile=_profile_sampler(vertices[0], segments))


def _profile_sampler(first: np.ndarray, segments: list[tuple[float, Any, np.ndarray]],
                     ) -> Callable[[np.ndarray], np.ndarray]:
    """Positions at given times along rest-to-rest Ruckig segments that follow each other
    (the first vertex before them, the last after them)."""
    starts = np.array([t0 for t0, _, _ in segments])

    def sample(times: np.ndarray) -> np.ndarray:
        out = np.empty((len(times), len(first)))
        which = np.searchsorted(starts, times, side="right") - 1
        for k, (t, i) in enumerate(zip(np.asarray(times).tolist(), which.tolist(),
                                       strict=True)):
            if i < 0:
                out[k] = first
                continue
            t0, profile, end = segments[i]
            if t - t0 >= profile.duration:
                out[k] = end
            else:
                out[k] = profile.at_time(t - t0)[0]
        return out

    return sample


def time_along_path(names: Sequence[str], states: np.ndarray, arc_m: np.ndarray,
                    limits: JointLimits, speed_m_s: float, accel_m_s2: float,
                    world: dict[str, np.ndarray] | None = None) -> JointTrajectory:
    """Time a dense path that follows a curve (the arm pulling a handle, the tool moving
    straight): along the curve's length `arc_m` (per state, from 0, never decreasing) the
    tool moves from rest to rest at most at `speed_m_s`, speeding up and slowing down at
    most at `accel_m_s2`, and on each segment at most as fast as keeps every joint within
    its velocity limit. A segment where a joint limits the speed slows down the tool there
    alone, not the whole path (slowing the whole path once stretched a placing of c3's milk
    to 0.1 mm/s: 270 s of the robot's time); a segment where the joints turn while the tool
    does not move takes its joints' time, the tool at rest. The states are close together
    (a few centimetres of the curve), so the turns between them are small."""
    names = tuple(names)
    states = np.asarray(states, dtype=float)
    arc = np.asarray(arc_m, dtype=float)
    if len(arc) != len(states) or not np.all(np.isfinite(arc)) or np.any(np.diff(arc) < 0):
        raise ValueError("time_along_path: arc_m needs one finite, non-decreasing length "
                         "per state")
    velocity = np.array([limits.velocity[n] for n in names])
    if len(states) < 2:
        return JointTrajectory(names, states, np.zeros(len(states)), world or {})
    ds = np.diff(arc)
    joints_s = (np.abs(np.diff(states, axis=0)) / velocity).max(axis=1)  # (at their limits)
    with np.errstate(divide="ignore", invalid="ignore"):
        cap = np.minimum(speed_m_s, np.where(joints_s > 0, ds / joints_s, np.inf))
    # the tool's speed at each state: within the caps of the segments on either side,
    # from rest to rest, changing at most at the acceleration
    speeds = [0.0, *np.minimum(cap[:-1], cap[1:]).tolist(), 0.0]
    reach = (2 * accel_m_s2 * ds).tolist()
    for k in range(len(ds)):
        speeds[k + 1] = min(speeds[k + 1], math.sqrt(speeds[k] ** 2 + reach[k]))
    for k in range(len(ds) - 1, -1, -1):
        speeds[k] = min(speeds[k], math.sqrt(speeds[k + 1] ** 2 + reach[k]))
    dt = np.array([_segment_time(length, speeds[k], speeds[k + 1], top, accel_m_s2)
                   for k, (length, top) in enumerate(zip(ds.tolist(), cap.tolist(),
                                                           strict=True))])
    # each joint (and the tool along the curve) changes its speed between neighbouring
    # segments at most at its acceleration: where the curve turns a joint round, the
    # segments on either side take longer
    steps = np.column_stack([np.diff(states, axis=0), ds])
    accel = np.array([*(limits.acceleration[n] for n in names), accel_m_s2])
    dt = limit_accelerations(steps, np.maximum(dt, joints_s), accel)
    times = np.concatenate([[0.0], np.cumsum(dt)])
    return JointTrajectory(names, states, times, world or {})


#: Forward and backward passes of `limit_accelerations` before it gives up finding the
#: segments' speeds one by one and slows the whole path instead.
ACCELERATION_PASSES = 50


def limit_accelerations(steps: np.ndarray, dt: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """Segment times, each at least as long as given, with which every coordinate's speed
    (steps: segments x coordinates) changes between neighbouring segments, and from rest
    before the first and to rest after the last, at most at its acceleration (`accel`, one
    per coordinate), as finite differences of the timed states measure it:
    |v_k - v_k-1| <= a (dt_k-1 + dt_k) / 2.

    Each segment keeps its direction and runs at a share s_k <= 1 of the speed it was
    given (dt_k = given_k / s_k). Forward and backward passes lower each share to the
    most its junctions with the segments before and after allow, until none changes: a
    junction that turns a joint round is passed slowly, and the segments around it slow
    down to it and speed up after it at the acceleration. (Finite differences would also
    pass one segment crawling between fast ones, its long time hiding the change of
    speed: no robot moves so, and the shares kept are those on the side of the neighbour's
    speed.) Should the passes not settle, the whole path is slowed by the factor that
    meets every junction (slowing all by f divides each change of speed by f and
    multiplies its time by f). Segments of no time (that move nothing) are left out."""
    dt = np.array(dt, dtype=float)
    steps = np.asarray(steps, dtype=float)
    accel = np.asarray(accel, dtype=float)
    timed = np.flatnonzero(dt > 0)
    if np.any(np.abs(np.delete(steps, timed, axis=0)) > 0):
        raise ValueError("limit_accelerations: a segment that moves needs time")
    steps = steps[timed]  # (a state written twice is one state, as a trace check sees it)
    if not len(timed) or _junction_ratios(steps, dt[timed], accel).max() <= 1.0 + 1e-9:
        return dt
    given = dt[timed].tolist()
    speed = (steps / dt[timed][:, None]).tolist()  # (each one's velocity as given)
    share = [1.0] * len(timed)
    rest = [0.0] * steps.shape[1]
    limits = accel.tolist()
    last = len(share) - 1

    def most(k: int, other: int | None) -> float:
        if other is None:
            return _share_most(speed[k], given[k], rest, 0.0, limits)
        return _share_most(speed[k], given[k], [v * share[other] for v in speed[other]],
                           given[other] / share[other], limits)

    for _ in range(ACCELERATION_PASSES):
        before = list(share)
        share[0] = min(share[0], most(0, None))
        for k in range(1, last + 1):
            share[k] = min(share[k], most(k, k - 1))
        share[last] = min(share[last], most(last, None))
        for k in range(last - 1, -1, -1):
            share[k] = min(share[k], most(k, k + 1))
        if share == before:
            break
    timed_dt = np.array(given) / np.array(share)
    worst = float(_junction_ratios(steps, timed_dt, accel).max())
    if worst > 1.0 + 1e-9:
        timed_dt *= math.sqrt(worst) * (1 + 1e-12)
    out = dt.copy()
    out[timed] = timed_dt
    return out


def _share_most(velocity: list[float], given: float, other_velocity: list[float],
                other_dt: float, accel: list[float]) -> float:
    """The largest share s of `velocity` (a segment given `given` seconds) that keeps its
    junction with a neighbour moving at `other_velocity` for `other_dt` seconds: per
    coordinate |s v - c| s <= a (other_dt s + given) / 2, below the share where the
    segment would outrun the neighbour (or turn against it) too fast."""
    best = math.inf
    for v, c, a in zip(velocity, other_velocity, accel, strict=True):
        b, d = a * other_dt / 2, a * given / 2
        av, ac = abs(v), abs(c)
        if v * c > 0:  # the same way: |s v - c| falls to 0 at s = c / v, then grows
            high = ((ac + b) + math.sqrt((ac + b) ** 2 + 4 * av * d)) / (2 * av)
        elif av > 0:  # the other way, or from rest: |s v - c| = s |v| + |c|
            high = (-(ac - b) + math.sqrt((ac - b) ** 2 + 4 * av * d)) / (2 * av)
        elif ac > b:  # (this coordinate stands here, the neighbour's moves)
            high = d / (ac - b)
        else:
            continue
        best = min(best, high)
    return best


def _junction_ratios(steps: np.ndarray, dt: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """At each junction of segments that take time (before the first, between each two,
    after the last): the largest change of speed over what the acceleration allows there
    (<= 1: kept)."""
    v = steps / dt[:, None]
    zero = np.zeros((1, steps.shape[1]))
    change = np.abs(np.diff(np.vstack([zero, v, zero]), axis=0))
    lengths = np.concatenate([[0.0], dt, [0.0]])
    allowed = accel[None, :] * ((lengths[:-1] + lengths[1:]) / 2)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(change > 0, change / allowed, 0.0)
    return ratio.max(axis=1)


def _segment_time(length: float, v0: float, v1: float, top: float, accel: float) -> float:
    """The least time to move `length` from speed v0 to v1, at most `top` and `accel`
    (speeding up, perhaps cruising, slowing down; 0 for no length or no speed)."""
    if length <= 0:
        return 0.0
    peak = min(top, math.sqrt((2 * accel * length + v0 * v0 + v1 * v1) / 2))
    if peak <= 0:
        return 0.0
    cruise = max(0.0, length - (2 * peak * peak - v0 * v0 - v1 * v1) / (2 * accel))
    return (2 * peak - v0 - v1) / accel + cruise / peak
