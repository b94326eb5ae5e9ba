"""Arm inverse kinematics for the PR2 with Pinocchio.

From a seed (the last solution, an arm reaching forward): damped least squares on the
SE(3) log error (Pinocchio's standard 6D IK), joint limits enforced by clamping after
each step; it keeps nearby targets' solutions near each other (a handle followed, a
pre-grasp beside its grasp). The torso height is part of the solution: with it the arm
is redundant (8 joints for a 6D pose), and the null space pulls the torso toward a
preferred height, so solutions keep the torso up (and the other, parked arm clear of
tables). Where that descent fails, or there is no seed, the arm's closed form
(`cramlite.motion.closed_form_ik`) gives the solution nearest the seed, or says at once
that there is none; a model not shaped as a PR2 arm gets descents from random starts
instead. The reduced model (torso + one arm, everything else locked) is built once per
arm and process, never per call.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.motion.closed_form_ik import ClosedFormArmIK, arm_geometry
from cramlite.motion.trajectory import wrap_angle
from cramlite.process_cache import ProcessCache
from cramlite.scene.models import pr2_model
from cramlite.world.pr2 import TORSO_JOINT

ARMS = ("right", "left")
ARM_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "upper_arm_roll_joint",
              "elbow_flex_joint", "forearm_roll_joint", "wrist_flex_joint", "wrist_roll_joint")


def arm_prefix(arm: str) -> str:
    if arm not in ARMS:
        raise ValueError(f"arm must be one of {ARMS}, got {arm!r}")
    return arm[0]


def arm_joint_names(arm: str) -> list[str]:
    return [f"{arm_prefix(arm)}_{j}" for j in ARM_JOINTS]


def tool_frame(arm: str) -> str:
    return f"{arm_prefix(arm)}_gripper_tool_frame"


EYE6 = np.eye(6)
#: Torso heights the closed form tries when the torso is free and the wanted one fails.
TORSO_HEIGHTS = 32
#: Targets whose closed-form solutions an arm's solver remembers (~4 KB each).
CLOSED_FORM_TARGETS = 5_000
#: Descents from seeded starts an arm's solver remembers (~1 KB each).
SEEDED_DESCENTS = 20_000


@dataclass(frozen=True)
class IKOptions:
    """Solver settings (pyroboplan style: a plain options object beside the solver)."""

    max_iterations: int = 150
    position_tolerance_m: float = 1e-3
    rotation_tolerance_rad: float = 1e-2
    damping: float = 1e-2
    restarts: int = 8
    #: Stop a restart early if the error has not halved in this many iterations.
    stall_iterations: int = 15
    #: Gain of the null-space pull toward the preferred torso height.
    torso_preference_gain: float = 0.5
    #: With a preferred torso height, the torso's share of each step (weighted least
    #: squares: 1 = like any joint; less keeps the torso near where the descent started).
    torso_weight: float = 0.2
    #: A solution with an arm joint closer than this to a limit is kept only if no start
    #: gives a better one (one away from the limits leaves room to approach and lift).
    limit_margin_rad: float = 0.1
    #: Where the seed's descent fails (or there is no seed), take the closed-form solution
    #: nearest the seed (`cramlite.motion.closed_form_ik`) instead of descents from random
    #: starts; a solve asked for no restarts (`restarts=0`) with a seed is its descent
    #: alone, as before. (A model not shaped as a PR2 arm always uses the random starts.)
    closed_form: bool = True


@dataclass(frozen=True)
class IKSolution:
    joints: dict[str, float]  # torso + arm joint angles by name
    position_error_m: float
    rotation_error_rad: float
    iterations: int


def _chain_length(model: pin.Model, start: int, end: int) -> float:
    """The sum of the offsets between the joints from `start` to `end` (a descendant):
    no configuration puts `end` farther from `start`."""
    total, joint = 0.0, end
    while joint != start:
        if joint <= 0:
            raise ValueError(f"joint {model.names[end]} is not below {model.names[start]}")
        total += float(np.linalg.norm(model.jointPlacements[joint].translation))
        joint = int(model.parents[joint])
    return total


class ArmIK:
    """IK for one arm (optionally with the torso) in the robot's base_footprint frame.
    One thread at a time: a solve works in the solver's own Pinocchio data (and what a
    descent from a seeded start finds is kept, see `_descend_from_seed`)."""

    def __init__(self, arm: str, with_torso: bool = True, options: IKOptions | None = None):
        self.arm = arm
        self.options = options or IKOptions()
        full = pr2_model().model
        keep = ([TORSO_JOINT] if with_torso else []) + arm_joint_names(arm)
        lock = [full.getJointId(n) for n in full.names[1:] if n not in keep]
        self.model = pin.buildReducedModel(full, lock, pin.neutral(full))
        self.data = self.model.createData()
        self.frame_id = self.model.getFrameId(tool_frame(arm))
        self.joint_names = [self.model.names[i] for i in range(1, self.model.njoints)]
        self._continuous = [self.model.nqs[i] == 2 for i in range(1, self.model.njoints)]
        self._idx_q = [int(self.model.idx_qs[i]) for i in range(1, self.model.njoints)]
        lower, upper = self.model.lowerPositionLimit, self.model.upperPositionLimit
        #: (q index, v index, lower, upper) of the joints with limits
        self._bounded_v = [(i, int(self.model.idx_vs[j]), lower[i], upper[i])
                           for j, i, cont in zip(range(1, self.model.njoints), self._idx_q,
                                                 self._continuous, strict=True) if not cont]
        self._bounded = [(i, lo, hi) for i, _, lo, hi in self._bounded_v]
        torso_q = (int(self.model.idx_qs[self.model.getJointId(TORSO_JOINT)])
                   if TORSO_JOINT in self.joint_names else -1)
        self._arm_bounded = [b for b in self._bounded if b[0] != torso_q]
        self._torso = None
        if TORSO_JOINT in self.joint_names:
            jid = self.model.getJointId(TORSO_JOINT)
            self._torso = (int(self.model.idx_qs[jid]), int(self.model.idx_vs[jid]))
        self._shoulder, self._reach, self._wrist, self._wrist_reach = self._reach_bounds()
        geometry = (arm_geometry(self.model, arm_prefix(arm), self.frame_id, TORSO_JOINT)
                    if self.options.closed_form else None)
        self._closed_form = ClosedFormArmIK(geometry) if geometry is not None else None
        #: The closed form's solutions by target and torso heights, kept for the process
        #: (a pure function of them; each trial of a setup asks the ones the last asked).
        self._solved: ProcessCache[np.ndarray] = ProcessCache(CLOSED_FORM_TARGETS)
        self._damped_eye = self.options.damping * EYE6  # (the damping term of every step)
        #: Descents from seeded starts (see `_descend_from_seed`), kept for the process.
        self._seeded: ProcessCache[IKSolution | None] = ProcessCache(SEEDED_DESCENTS)

    def _reach_bounds(self) -> tuple[np.ndarray, float, np.ndarray, float]:
        """The shoulder's position (torso at 0); the farthest the tool frame gets from it
        (the arm stretched out; sampled configurations too, plus 2 cm); the wrist's centre
        in the tool frame (where the wrist's joints meet: fixed behind the fingers); and the
        farthest the wrist gets from the shoulder (likewise). A target that puts either out
        of range has no solution, and saying so takes no descent: a handle facing away from
        the shoulder is near enough for the fingers, not for the wrist.

        No distance can exceed the sum of the offsets along the chain; where the neutral
        configuration reaches that sum (the PR2's arm stretched straight out), it is the
        farthest, and no sample is drawn (500 forward kinematics an arm saved)."""
        model, data = self.model, self.data
        shoulder = model.getJointId(f"{arm_prefix(self.arm)}_shoulder_pan_joint")
        wrist = model.getJointId(f"{arm_prefix(self.arm)}_wrist_flex_joint")
        tool_joint = int(model.frames[self.frame_id].parentJoint)
        tool_bound = _chain_length(model, shoulder, tool_joint) + float(
            np.linalg.norm(model.frames[self.frame_id].placement.translation))
        wrist_bound = _chain_length(model, shoulder, wrist)
        rng = np.random.default_rng(0)
        reach = wrist_reach = 0.0
        shoulder_at = in_tool = np.zeros(3)
        for k in range(501):
            q = pin.neutral(model) if k == 0 else self.random_q(rng)
            if self._torso is not None:
                q[self._torso[0]] = 0.0
            pin.forwardKinematics(model, data, q)
            origin = data.oMi[shoulder].translation
            tool = pin.updateFramePlacement(model, data, self.frame_id).translation - origin
            to_wrist = data.oMi[wrist].translation - origin
            # (np.linalg.norm's own arithmetic, without its checks: 500 samples an arm)
            reach = max(reach, math.sqrt(tool.dot(tool)))
            wrist_reach = max(wrist_reach, math.sqrt(to_wrist.dot(to_wrist)))
            if k == 0:  # (the shoulder and the wrist in the tool frame: the same in any)
                shoulder_at = data.oMi[shoulder].translation.copy()
                in_tool = data.oMf[self.frame_id].actInv(data.oMi[wrist]).translation.copy()
                if reach >= tool_bound - 1e-12 and wrist_reach >= wrist_bound - 1e-12:
                    break  # (the neutral configuration is the farthest there is)
        return shoulder_at, reach + 0.02, in_tool, wrist_reach + 0.02

    def out_of_reach(self, target: pin.SE3, fixed_torso_m: float | None = None) -> bool:
        """Is the target surely out of reach of the fingers or of the wrist, at the given
        torso height (or at any height the torso can take)?"""
        fingers = np.asarray(target.translation)
        wrist = fingers + np.asarray(target.rotation) @ self._wrist
        return (self._distance(fingers, fixed_torso_m) > self._reach or
                self._distance(wrist, fixed_torso_m) > self._wrist_reach)

    def _distance(self, point: np.ndarray, fixed_torso_m: float | None) -> float:
        """From the shoulder to a point, the torso at the given height (or at the height
        that brings the shoulder closest)."""
        x, y, z = point - self._shoulder
        if self._torso is None:
            dz = z
        elif fixed_torso_m is not None:
            dz = z - fixed_torso_m
        else:
            lo = self.model.lowerPositionLimit[self._torso[0]]
            hi = self.model.upperPositionLimit[self._torso[0]]
            dz = z - min(max(z, lo), hi)
        return math.sqrt(x * x + y * y + dz * dz)

    # -- conversions -------------------------------------------------------------------
    def to_q(self, joints: dict[str, float]) -> np.ndarray:
        q = pin.neutral(self.model)
        for name, i, cont in zip(self.joint_names, self._idx_q, self._continuous, strict=True):
            if name in joints:
                if cont:
                    q[i], q[i + 1] = np.cos(joints[name]), np.sin(joints[name])
                else:
                    q[i] = joints[name]
        return q

    def from_q(self, q: np.ndarray) -> dict[str, float]:
        out = {}
        for name, i, cont in zip(self.joint_names, self._idx_q, self._continuous, strict=True):
            out[name] = float(np.arctan2(q[i + 1], q[i])) if cont else float(q[i])
        return out

    def random_q(self, rng: np.random.Generator) -> np.ndarray:
        """A configuration drawn uniformly within the limits (a continuous joint's angle
        within a turn), one draw per joint: the limited joints', then the continuous'."""
        draw_lo, draw_hi, bounded, continuous, neutral = self._draws
        q = neutral.copy()
        values = rng.uniform(draw_lo, draw_hi)  # (one call: the same numbers, in order)
        q[bounded] = values[:len(bounded)]
        for i, a in zip(continuous, values[len(bounded):].tolist(), strict=True):
            q[i], q[i + 1] = np.cos(a), np.sin(a)
        return q

    @functools.cached_property
    def _draws(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int], np.ndarray]:
        """(lower and upper bounds of each draw, the limited joints' and the continuous
        joints' q indices, the neutral configuration) for `random_q`."""
        continuous = [i for i, cont in zip(self._idx_q, self._continuous, strict=True)
                      if cont]
        lows = [lo for _, lo, _ in self._bounded] + [-np.pi] * len(continuous)
        highs = [hi for _, _, hi in self._bounded] + [np.pi] * len(continuous)
        return (np.array(lows, dtype=float), np.array(highs, dtype=float),
                np.array([i for i, _, _ in self._bounded], dtype=int), continuous,
                pin.neutral(self.model))

    def forward(self, joints: dict[str, float]) -> pin.SE3:
        """The tool frame's pose (base frame) at these joints."""
        pin.forwardKinematics(self.model, self.data, self.to_q(joints))
        return pin.updateFramePlacement(self.model, self.data, self.frame_id).copy()

    def between(self, a: dict[str, float], b: dict[str, float], f: float,
                ) -> dict[str, float]:
        """The joints a fraction `f` of the straight way from `a` to `b` (a continuous
        joint the short way round, as `JointLimits.unwrap_goal` turns it)."""
        out = {}
        for name, cont in zip(self.joint_names, self._continuous, strict=True):
            start, step = a[name], b[name] - a[name]
            out[name] = start + f * (wrap_angle(step) if cont else step)
        return out

    # -- solving -----------------------------------------------------------------------
    def solve(self, target: pin.SE3, rng: np.random.Generator,
              seed_joints: dict[str, float] | None = None,
              preferred_torso_m: float | None = None,
              fixed_torso_m: float | None = None,
              restarts: int | None = None,
              near_limits_ok: bool = False) -> IKSolution | None:
        """Joint angles that put the tool frame at `target` (base frame), or None.

        `fixed_torso_m`: keep the torso at this height (the PR2's torso moves at 1.3 cm/s,
        so a solution that keeps it saves seconds of robot time). `near_limits_ok`: the
        first solution found is enough, even one close to a joint limit (to learn whether a
        target can be reached at all, not how best)."""
        opts = self.options
        if self.out_of_reach(target, fixed_torso_m):
            return None
        restarts = opts.restarts if restarts is None else restarts
        torso = None if fixed_torso_m is None or self._torso is None else self._torso
        fallback = None
        for attempt in range(restarts + 1):  # (random starts drawn only when needed)
            if attempt == (1 if seed_joints else 0) and self._closed_form is not None:
                # (the seed's descent failed or there is none: the closed form instead of
                # descents from random starts)
                return self._from_closed_form(target, rng, seed_joints, preferred_torso_m,
                                              fixed_torso_m, near_limits_ok) or fallback
            q0 = self.to_q(seed_joints) if seed_joints and attempt == 0 \
                else self.random_q(rng)
            if torso is not None:
                q0[torso[0]] = fixed_torso_m
            elif preferred_torso_m is not None and self._torso is not None:
                # start where the torso is wanted: the null-space pull only keeps it there
                # (a descent converges in a few steps, too few for the pull to move it far)
                iq = self._torso[0]
                q0[iq] = min(max(preferred_torso_m, self.model.lowerPositionLimit[iq]),
                             self.model.upperPositionLimit[iq])
            descend = self._descend_from_seed if attempt == 0 and seed_joints \
                else self._descend
            result = descend(q0, target, preferred_torso_m, fixed_torso=torso is not None)
            if result is None:
                continue
            if near_limits_ok or self._clear_of_limits(result.joints):
                return result
            fallback = fallback or result
        return fallback

    def _from_closed_form(self, target: pin.SE3, rng: np.random.Generator,
                          seed_joints: dict[str, float] | None,
                          preferred_torso_m: float | None, fixed_torso_m: float | None,
                          near_limits_ok: bool) -> IKSolution | None:
        """The closed-form solution nearest the seed, one clear of the joint limits if
        there is one (unless `near_limits_ok`); without a seed, nearest a configuration
        drawn at random (as a random start would be: asked again, another solution); the
        torso at `fixed_torso_m`, else at the preferred height if that reaches, else at
        the nearest height that does (of those with a solution clear of the limits, if
        any), both within the torso's range (as a descent clamps it)."""
        solver = self._closed_form
        assert solver is not None
        names = self.joint_names
        seed = self._reference(seed_joints if seed_joints else self.from_q(self.random_q(rng)))
        lo, hi = solver.geometry.torso or (0.0, 0.0)
        wanted = fixed_torso_m if fixed_torso_m is not None else preferred_torso_m
        wanted = min(max(seed[0] if wanted is None else wanted, lo), hi)
        if self._torso is None:
            heights = [[0.0]]
        elif fixed_torso_m is not None:
            heights = [[wanted]]
        else:
            grid = np.linspace(lo, hi, TORSO_HEIGHTS)
            heights = [[wanted], grid[np.argsort(np.abs(grid - wanted), kind="stable")]]
        for torsos in heights:
            found = self._all_solutions(target, torsos)
            if len(found):
                break
        else:
            return None
        if self._torso is None:
            found = found[:, 1:]
        if not near_limits_ok:
            clear = self._clear_rows(found)
            found = found[clear] if clear.any() else found
        if self._torso is not None:  # (the torso moves at 1.3 cm/s: the nearest height)
            off = np.abs(found[:, 0] - wanted)
            found = found[off <= off.min() + 1e-12]
        best = found[int(np.argmin(self._distances(found, seed)))]
        joints = {name: float(v) for name, v in zip(names, best, strict=True)}
        q0 = self.to_q(joints)
        # (exact to rounding: the descent confirms it at its first step, or polishes it)
        return self._descend(q0, target, None, fixed_torso=self._torso is not None)

    def _all_solutions(self, target: pin.SE3, torsos: Sequence[float]) -> np.ndarray:
        """`ClosedFormArmIK.solutions`, remembered (read-only rows)."""
        solver = self._closed_form
        assert solver is not None
        heights = np.asarray(torsos, dtype=float)

        def solve() -> np.ndarray:
            rows = solver.solutions(target.rotation, target.translation, heights)
            rows.flags.writeable = False
            return rows

        key = (target.homogeneous.tobytes(), heights.tobytes())
        return self._solved.get_or_compute(key, solve)

    def _reference(self, seed_joints: dict[str, float]) -> np.ndarray:
        """The seed as a row of joint values (the middle of each joint's range where it
        names no value; 0 for a continuous joint)."""
        row = []
        for name, i, cont in zip(self.joint_names, self._idx_q, self._continuous,
                                 strict=True):
            if name in seed_joints:
                row.append(float(seed_joints[name]))
            elif cont:
                row.append(0.0)
            else:
                row.append(0.5 * (self.model.lowerPositionLimit[i] +
                                  self.model.upperPositionLimit[i]))
        return np.array(row)

    def _distances(self, rows: np.ndarray, seed: np.ndarray) -> np.ndarray:
        """Squared joint-space distances of configurations (N x joints) from the seed (a
        continuous joint the short way round; the torso in decimetres)."""
        diff = rows - seed
        cont = np.asarray(self._continuous)
        diff[:, cont] = wrap_angle(diff[:, cont])
        if self._torso is not None:
            diff[:, 0] *= 10.0
        return np.einsum("ij,ij->i", diff, diff)

    def _clear_rows(self, rows: np.ndarray) -> np.ndarray:
        """`_clear_of_limits` of each configuration (N x joints)."""
        margin = self.options.limit_margin_rad
        ok = np.ones(len(rows), dtype=bool)
        columns = {i: k for k, i in enumerate(self._idx_q)}
        for i, lo, hi in self._arm_bounded:
            column = rows[:, columns[i]]
            ok &= (column >= lo + margin) & (column <= hi - margin)
        return ok

    def _descend_from_seed(self, q0: np.ndarray, target: pin.SE3,
                           preferred_torso_m: float | None = None,
                           fixed_torso: bool = False) -> IKSolution | None:
        """`_descend` from a start that is not drawn at random, remembered: a pure function
        of its arguments (and of the solver's model and options, fixed when it is made),
        and location designators ask the same ones again and again (each trial of a setup
        starts as the last one did). The answer is the one the descent gives, and no
        random number is drawn either way."""
        key = (q0.tobytes(), target.homogeneous.tobytes(), preferred_torso_m, fixed_torso)
        result = self._seeded.get_or_compute(key, lambda: self._descend(
            q0, target, preferred_torso_m, fixed_torso=fixed_torso))
        return None if result is None else dataclasses.replace(result,
                                                               joints=dict(result.joints))

    def _clear_of_limits(self, joints: dict[str, float]) -> bool:
        margin = self.options.limit_margin_rad
        q = self.to_q(joints)
        return all(lo + margin <= q[i] <= hi - margin for i, lo, hi in self._arm_bounded)

    def _descend(self, q: np.ndarray, target: pin.SE3,
                 preferred_torso_m: float | None = None,
                 fixed_torso: bool = False) -> IKSolution | None:
        opts, model, data, fid = self.options, self.model, self.data, self.frame_id
        best, best_at = np.inf, 0
        for it in range(opts.max_iterations):
            # (the tool frame alone: the reduced model has 164 frames, framesForwardKinematics
            # would place them all)
            pin.forwardKinematics(model, data, q)
            error_transform = pin.updateFramePlacement(model, data, fid).actInv(target)
            err = pin.log6(error_transform).vector
            ex, ey, ez, rx, ry, rz = err.tolist()
            pos_err = math.sqrt(ex * ex + ey * ey + ez * ez)
            rot_err = math.sqrt(rx * rx + ry * ry + rz * rz)
            if pos_err < opts.position_tolerance_m and rot_err < opts.rotation_tolerance_rad:
                return IKSolution(self.from_q(q), pos_err, rot_err, it)
            total = pos_err + rot_err
            if total < 0.5 * best:
                best, best_at = total, it
            elif it - best_at > opts.stall_iterations:
                return None
            jac = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            jac = pin.Jlog6(error_transform) @ jac
            if fixed_torso:
                jac[:, self._torso[1]] = 0.0
                preferred_torso_m = None
            v = self._step(jac, err, q, preferred_torso_m)
            # a joint at its limit that the step pushes further out is held there, and
            # the step is taken again without it (else the descent crawls along the limit)
            # (plain floats: comparing numpy scalars one by one costs more than the list)
            qs, vs = q.tolist(), v.tolist()
            held = [iv for iq, iv, lo, hi in self._bounded_v
                    if (qs[iq] <= lo and vs[iv] < 0) or (qs[iq] >= hi and vs[iv] > 0)]
            if held:
                for iv in held:  # (one or two: plain indexing costs less than a list's)
                    jac[:, iv] = 0.0
                torso_held = self._torso is not None and self._torso[1] in held
                v = self._step(jac, err, q, None if torso_held else preferred_torso_m)
                for iv in held:
                    v[iv] = 0.0
            q = pin.integrate(model, q, v)
            qs = q.tolist()
            for i, lo, hi in self._bounded:
                if qs[i] < lo:
                    q[i] = lo
                elif qs[i] > hi:
                    q[i] = hi
        return None

    def _step(self, jac: np.ndarray, err: np.ndarray, q: np.ndarray,
              preferred_torso_m: float | None) -> np.ndarray:
        """Damped least squares, v = J^T (J J^T + damping I)^-1 err. With a preferred torso
        height, the torso's column is weighted down (the arm does most of the work, so the
        torso stays near the height it started at) and a pull toward the preference is
        added in the null space. (See `_solve_spd` for the solver.)"""
        if preferred_torso_m is None or self._torso is None:
            return jac.T @ _solve_spd(jac @ jac.T + self._damped_eye, err)
        iq, iv = self._torso
        weight = self.options.torso_weight
        jac = jac.copy()
        jac[:, iv] *= weight
        pull = np.zeros(self.model.nv)
        pull[iv] = self.options.torso_preference_gain * (preferred_torso_m - q[iq])
        gram = jac @ jac.T + self._damped_eye
        w = _solve_spd(gram, np.column_stack([err, jac @ pull]))
        v = jac.T @ w[:, 0] + pull - jac.T @ w[:, 1]
        v[iv] *= weight
        return v


def _solve_spd(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with matrix @ x = rhs (the matrix is symmetric positive definite: damped).

    numpy's LAPACK solve gufuncs directly: 1 us on a 6x6 matrix, where np.linalg.solve's
    checks cost 5 us (a v1 trial solves ~5000 of them) and scipy.linalg's dposv, as fast,
    costs 0.25 s to import. np.linalg.solve where the gufuncs are missing."""
    if _GUFUNC_SOLVE is None:
        return np.linalg.solve(matrix, rhs)
    return _GUFUNC_SOLVE[rhs.ndim == 1](matrix, rhs)


try:  # (numpy's own LAPACK wrappers, numpy 1.x and 2.x alike)
    from numpy.linalg import _umath_linalg

    _GUFUNC_SOLVE = (_umath_linalg.solve, _umath_linalg.solve1)
except (ImportError, AttributeError):  # pragma: no cover - another numpy
    _GUFUNC_SOLVE = None


@functools.cache
def arm_ik(arm: str, with_torso: bool = True) -> ArmIK:
    """The IK solver of an arm, built once per process (the model is never rebuilt)."""
    return ArmIK(arm, with_torso)
