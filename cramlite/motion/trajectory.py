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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

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


def wrap_angle(a: float) -> float:
    """Into [-pi, pi)."""
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

    @property
    def duration_s(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0

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
        t0 += float(profile.duration)
        positions.append(b)
        times.append(t0)
    times_arr = np.maximum.accumulate(np.array(times))  # guard against rounding
    return JointTrajectory(names, np.array(positions), times_arr)


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
    times = np.concatenate([[0.0], np.cumsum(np.maximum(dt, joints_s))])
    return JointTrajectory(names, states, times, world or {})


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
