"""Every IK solution of a PR2 arm for one tool pose, in closed form, over a fine grid of
shoulder pan angles (and of torso heights).

The PR2's arm has a shoulder offset (the lift axis 10 cm out from the pan axis), an
upper arm and forearm along one line when the elbow is straight, and a wrist whose three
axes meet in one point. With the pan (and torso) fixed, the rest follows: the wrist's
centre sits a fixed distance behind the tool frame; its distance from the lift axis gives
the elbow; the side-to-side part of where it lies gives the upper arm's roll (two ways),
the rest the lift; the wrist's angles are those of the rotation left over (an x-y-x
decomposition; the flex joint bends one way only, so one). This is what the PR2's own
analytic solver (pr2_arm_kinematics) does with the upper arm roll as the free angle.

Written here because neither Pinocchio nor any library on PyPI solves a PR2 arm in closed
form: the damped least-squares descent of `cramlite.motion.ik` needs random restarts,
most of which fail (72 % of its steps went into descents that failed), where this
answers whether a target can be reached, and with which configurations, in one pass. The
geometry is read from the robot's model and checked to have this shape; a model of
another shape gets no closed-form solver (`arm_geometry` returns None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.motion.trajectory import wrap_angle

#: The PR2 arm's joints in order, with the axis each turns about (x, y, z: 0, 1, 2) and
#: the offset from the joint before, along x, that makes the chain this solver knows.
CHAIN = (("shoulder_pan_joint", 2), ("shoulder_lift_joint", 1),
         ("upper_arm_roll_joint", 0), ("elbow_flex_joint", 1), ("forearm_roll_joint", 0),
         ("wrist_flex_joint", 1), ("wrist_roll_joint", 0))
#: Shoulder pan angles tried, one every this many radians (0.5 degrees: at the PR2's
#: longest reach of ~0.82 m a step moves the wrist 7 mm), and the pan that turns the
#: shoulder toward the wrist (a pose at the edge of reach). A target reachable only within
#: a narrower span of pan, where a joint is at its limit, may find no solution; with the
#: upper arm rolled a quarter turn the roll changes fast with the pan, and the solution
#: nearest a configuration may be a tenth of a radian from it. (0.25 degrees took a third
#: longer a solve.)
PAN_STEP_RAD = math.radians(0.5)


@dataclass(frozen=True)
class ArmGeometry:
    """Where a PR2 arm's joints are (base frame, torso at 0) and how far they may turn."""

    pan_origin: tuple[float, float, float]  #: the pan axis's point at torso height 0
    shoulder_m: float  #: pan axis to lift axis, along the upper arm's x
    upper_arm_m: float  #: lift (and roll) to elbow
    forearm_m: float  #: elbow to the wrist's centre
    tool_m: float  #: the wrist's centre to the tool frame, along its x
    torso: tuple[float, float] | None  #: the torso's range (None: no torso joint)
    pan: tuple[float, float]
    lift: tuple[float, float]
    roll: tuple[float, float]
    elbow: tuple[float, float]
    flex: tuple[float, float]


def arm_geometry(model: pin.Model, prefix: str, tool_frame_id: int,
                 torso_joint: str | None) -> ArmGeometry | None:
    """The geometry of the arm `prefix` ("r"/"l") in a model holding (the torso and) that
    arm; None unless its joints are laid out as a PR2 arm's (see `CHAIN`)."""
    names = list(model.names)
    offsets = []
    pan_origin = None
    limits = {}
    for k, (joint, axis) in enumerate(CHAIN):
        name = f"{prefix}_{joint}"
        if name not in names:
            return None
        jid = names.index(name)
        placement = model.jointPlacements[jid]
        kind = model.joints[jid].shortname()
        if not np.allclose(placement.rotation, np.eye(3)) or "XYZ"[axis] not in kind[-1:]:
            return None
        t = placement.translation
        if k == 0:
            pan_origin = t
        elif abs(t[1]) > 1e-9 or abs(t[2]) > 1e-9:
            return None
        else:
            offsets.append(float(t[0]))
        iq = int(model.idx_qs[jid])
        limits[joint] = (float(model.lowerPositionLimit[iq]),
                         float(model.upperPositionLimit[iq]))
    frame = model.frames[tool_frame_id]
    tool = frame.placement
    if names[frame.parentJoint] != f"{prefix}_wrist_roll_joint" or \
            not np.allclose(tool.rotation, np.eye(3)) or abs(tool.translation[1]) > 1e-9 \
            or abs(tool.translation[2]) > 1e-9:
        return None
    # offsets: lift, roll, elbow, forearm roll, flex, wrist roll (x along the arm)
    shoulder, roll_at, upper, forearm_roll_at, forearm, wrist_roll_at = offsets
    if roll_at or forearm_roll_at or wrist_roll_at:
        return None
    torso = None
    origin = np.asarray(pan_origin, dtype=float)
    pan_parent = model.parents[names.index(f"{prefix}_shoulder_pan_joint")]
    if torso_joint is not None and torso_joint in names:
        tid = names.index(torso_joint)
        if pan_parent != tid or model.joints[tid].shortname() != "JointModelPZ" or \
                not np.allclose(model.jointPlacements[tid].rotation, np.eye(3)):
            return None
        origin = origin + model.jointPlacements[tid].translation
        iq = int(model.idx_qs[tid])
        torso = (float(model.lowerPositionLimit[iq]), float(model.upperPositionLimit[iq]))
    elif pan_parent != 0:
        return None
    return ArmGeometry(tuple(float(v) for v in origin), shoulder, upper, forearm,
                       float(tool.translation[0]), torso, limits["shoulder_pan_joint"],
                       limits["shoulder_lift_joint"], limits["upper_arm_roll_joint"],
                       limits["elbow_flex_joint"], limits["wrist_flex_joint"])


class ClosedFormArmIK:
    """All the configurations (torso, pan, lift, roll, elbow, forearm roll, flex, wrist
    roll) that put an arm's tool frame at a pose, the pan on a grid of `pan_step_rad`."""

    def __init__(self, geometry: ArmGeometry, pan_step_rad: float = PAN_STEP_RAD):
        self.geometry = g = geometry
        count = max(2, int(math.ceil((g.pan[1] - g.pan[0]) / pan_step_rad)) + 1)
        self.pans = np.linspace(g.pan[0], g.pan[1], count)
        self._cos, self._sin = np.cos(self.pans), np.sin(self.pans)

    def solutions(self, rotation: np.ndarray, translation: np.ndarray,
                  torsos: np.ndarray | list[float]) -> np.ndarray:
        """N x 8 configurations within the joint limits, for each torso height given (in
        that order), pans ascending; the continuous joints (forearm and wrist roll) in
        [-pi, pi]. Besides the grid, the pan that turns the shoulder toward the wrist's
        centre (where the elbow bends most: a pose at the edge of the arm's reach, the
        elbow nearly straight, may be reached only near it)."""
        g = self.geometry
        rotation = np.asarray(rotation, dtype=float)
        translation = np.asarray(translation, dtype=float)
        torsos = np.atleast_1d(np.asarray(torsos, dtype=float))
        wrist = translation - g.tool_m * rotation[:, 0]
        # the vector from the lift axis's point to the wrist's centre, in the pan's frame
        # (T x P): the pan turns about z through pan_origin, the lift sits shoulder_m out
        dx = wrist[0] - g.pan_origin[0]
        dy = wrist[1] - g.pan_origin[1]
        dz = wrist[2] - g.pan_origin[2] - torsos  # T
        pans, c, s = self.pans, self._cos, self._sin
        toward = math.atan2(dy, dx)
        if g.pan[0] <= toward <= g.pan[1]:
            pans = np.append(pans, toward)
            c, s = np.append(c, math.cos(toward)), np.append(s, math.sin(toward))
        wx = (c * dx + s * dy) - g.shoulder_m  # P
        wy = -s * dx + c * dy  # P
        wz = np.broadcast_to(dz[:, None], (len(torsos), len(pans)))
        wx = np.broadcast_to(wx, wz.shape)
        wy = np.broadcast_to(wy, wz.shape)
        a, b = g.upper_arm_m, g.forearm_m
        cos_e = (wx * wx + wy * wy + wz * wz - a * a - b * b) / (2 * a * b)
        ok = (cos_e >= -1.0) & (cos_e <= 1.0)
        elbow = -np.arccos(np.clip(cos_e, -1.0, 1.0))
        ok &= (elbow >= g.elbow[0]) & (elbow <= g.elbow[1])
        fx = a + b * np.cos(elbow)
        fz = -b * np.sin(elbow)  # >= 0: the elbow bends one way
        with np.errstate(divide="ignore", invalid="ignore"):
            sin_r = np.where(fz > 1e-12, -wy / fz, 2.0)
        ok &= np.abs(sin_r) <= 1.0
        t_idx, p_idx = np.nonzero(ok)
        if not len(t_idx):
            return np.zeros((0, 8))
        r1 = np.arcsin(sin_r[t_idx, p_idx])
        # the roll's solutions: r1 and pi - r1, and those a turn away, within the limits
        rolls, rows = [], []
        for base in (r1, math.pi - r1):
            for turn in (-2 * math.pi, 0.0, 2 * math.pi):
                r = base + turn
                keep = (r >= g.roll[0]) & (r <= g.roll[1])
                rolls.append(r[keep])
                rows.append(np.flatnonzero(keep))
        roll = np.concatenate(rolls)
        row = np.concatenate(rows)
        ti, pi_ = t_idx[row], p_idx[row]
        e = elbow[ti, pi_]
        fxr, fzr = fx[ti, pi_], fz[ti, pi_]
        cz = fzr * np.cos(roll)
        lift = np.arctan2(cz, fxr) - np.arctan2(wz[ti, pi_], wx[ti, pi_])
        lift = wrap_angle(lift)
        keep = (lift >= g.lift[0]) & (lift <= g.lift[1])
        ti, pi_, roll, lift, e = ti[keep], pi_[keep], roll[keep], lift[keep], e[keep]
        if not len(ti):
            return np.zeros((0, 8))
        pan = pans[pi_]
        # the forearm's frame, Rz(pan) Ry(lift) Rx(roll) Ry(elbow), column by column (N x 3
        # each), and the rotation left for the wrist, Rx(forearm roll) Ry(flex) Rx(wrist
        # roll) = frame^T rotation: its entries are the columns' dot products with the
        # target's
        cp, sp, cl, sl = np.cos(pan), np.sin(pan), np.cos(lift), np.sin(lift)
        cr, sr, ce, se = np.cos(roll), np.sin(roll), np.cos(e), np.sin(e)
        zero = np.zeros_like(cp)
        a0 = np.column_stack([cp * cl, sp * cl, -sl])  # Rz Ry
        a1 = np.column_stack([-sp, cp, zero])
        a2 = np.column_stack([cp * sl, sp * sl, cl])
        b1 = a1 * cr[:, None] + a2 * sr[:, None]  # ... Rx
        b2 = a2 * cr[:, None] - a1 * sr[:, None]
        u0 = a0 * ce[:, None] - b2 * se[:, None]  # ... Ry
        u2 = a0 * se[:, None] + b2 * ce[:, None]
        m = np.stack([u0 @ rotation, b1 @ rotation, u2 @ rotation], axis=1)  # N x 3 x 3
        # (the flex from both its cosine and its sine: arccos alone cannot tell a wrist
        # bent by less than 1.5e-8 rad from a straight one, and the rolls would follow
        # rounding noise)
        bend = np.hypot(m[:, 1, 0], m[:, 2, 0])
        flex = -np.arctan2(bend, m[:, 0, 0])
        keep = (flex >= g.flex[0]) & (flex <= g.flex[1])
        straight = bend < 1e-12  # (the rolls add up: all in the wrist's)
        forearm_roll = np.where(straight, 0.0, np.arctan2(-m[:, 1, 0], m[:, 2, 0]))
        # the wrist's roll from what the forearm's roll and the flex leave, Rx(wrist roll) =
        # Ry(flex)^T Rx(forearm roll)^T m (its own entries of m would give it with an
        # error of its own, which a nearly straight wrist does not hide)
        ca, sa = np.cos(forearm_roll), np.sin(forearm_roll)
        cb, sb = np.cos(flex), np.sin(flex)
        wrist_roll = np.arctan2(sb * m[:, 0, 1] + cb * (ca * m[:, 2, 1] - sa * m[:, 1, 1]),
                                ca * m[:, 1, 1] + sa * m[:, 2, 1])
        out = np.column_stack([torsos[ti], pan, lift, roll, e, forearm_roll, flex,
                               wrist_roll])[keep]
        order = np.lexsort((out[:, 1], ti[keep]))  # by torso as given, then pan
        return out[order]
