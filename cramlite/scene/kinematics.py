"""World frames of the robot's links for many joint vectors at once (Pinocchio's model).

A motion's collision check needs every moving link's frame in every state of the motion.
For a few states Pinocchio's forward kinematics runs state by state; for more, the chain
is composed for all states at once (one matrix product per joint over the S states; the
joints that do not move are placed once, by Pinocchio, where the robot stands), which is
several times faster from 8 states on.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from cramlite.scene.models import ArticulatedModel

#: Fewer states than this are placed state by state (measured: from about 8 states on,
#: composing the chain for all states at once is faster).
FEW_STATES = 8


class BatchedFrames:
    """Link frames of one articulated model for rows of joint values."""

    def __init__(self, model: ArticulatedModel):
        self.articulated = model
        self.model = model.model
        self.data = self.model.createData()
        m = self.model
        self._slot = {name: (info.q_index, info.kind == "continuous")
                      for name, info in model.joints.items()}
        self._joint_id = {name: int(m.getJointId(name)) for name in model.joints}
        self._placement = {j: m.jointPlacements[j].homogeneous.copy() for j in range(1, m.njoints)}
        self._kind = {j: _joint_kind(m.joints[j]) for j in range(1, m.njoints)}
        #: link -> (the joint it rides on, its frame in that joint's frame)
        self._link = {name: (int(m.frames[fid].parentJoint),
                             m.frames[fid].placement.homogeneous.copy())
                      for name, fid in model.link_frames.items()}
        self._plans: dict[tuple[str, ...], tuple[list[int], list[int], np.ndarray]] = {}

    def frames(self, base: np.ndarray, values: dict[str, float] | np.ndarray,
               joints: Sequence[str], states: np.ndarray, links: Sequence[str]) -> np.ndarray:
        """World frames (S x L x 4 x 4) of `links`, with `joints` at each row of `states`
        and every other joint at `values` (by name, or Pinocchio's configuration), the
        model's root at `base` (4 x 4)."""
        states = np.asarray(states, dtype=float).reshape(len(states), len(joints))
        riding, columns, placements, per_link = self._plan(tuple(links))
        q = values.copy() if isinstance(values, np.ndarray) else self.articulated.q(values)
        if len(states) < FEW_STATES or any(self._kind[self._joint_id[n]][0] == "other"
                                           for n in joints):
            out = self._each_state(base, q, joints, states, riding)
            return out[:, columns] @ placements
        return self._all_states(base, q, joints, states, riding, per_link)

    def z_rows(self, q: np.ndarray, joints: Sequence[str], state: np.ndarray,
               links: Sequence[str]) -> np.ndarray:
        """The bottom row of each link's world rotation (L x 3: the world z components of
        its axes) with `joints` at `state` and every other joint as in `q` (Pinocchio's
        configuration, changed in place at `joints`' slots). The robot's base only turns
        about the vertical, which leaves these rows as they are. Cheaper than `frames` for
        one state: how far a held item tilts needs no more."""
        _put_state(q, [self._slot[n] for n in joints], state)
        pin.forwardKinematics(self.model, self.data, q)
        placed = self.data.oMi
        return np.array([placed[self._link[link][0]].rotation[2] @ self._link[link][1][:3, :3]
                         for link in links])

    def _plan(self, links: tuple[str, ...],
              ) -> tuple[list[int], list[int], np.ndarray, list[tuple[int, np.ndarray | None]]]:
        """For a tuple of links: the joints they ride on, each link's column among them,
        each link's frame in its joint's frame, and per link (its joint, that frame or None
        where it is the joint's own) (kept: a motion asks the same links)."""
        plan = self._plans.get(links)
        if plan is None:
            riding = sorted({self._link[link][0] for link in links})
            column = {j: k for k, j in enumerate(riding)}
            per_link = [(joint, None if np.array_equal(frame, np.eye(4)) else frame)
                        for joint, frame in (self._link[link] for link in links)]
            plan = self._plans[links] = (
                riding, [column[self._link[link][0]] for link in links],
                np.array([self._link[link][1] for link in links]).reshape(-1, 4, 4), per_link)
        return plan

    def _each_state(self, base: np.ndarray, q: np.ndarray, joints: Sequence[str],
                    states: np.ndarray, riding: list[int]) -> np.ndarray:
        model, data = self.model, self.data
        slots = [self._slot[n] for n in joints]
        out = np.empty((len(states), len(riding), 4, 4))
        placed = data.oMi  # (the vector Pinocchio fills in place: one lookup, not R a state)
        for s, row in enumerate(states):
            _put_state(q, slots, row)
            pin.forwardKinematics(model, data, q)
            out[s] = [placed[j].homogeneous for j in riding]
        return base @ out

    def _all_states(self, base: np.ndarray, q: np.ndarray, joints: Sequence[str],
                    states: np.ndarray, riding: list[int],
                    per_link: list[tuple[int, np.ndarray | None]]) -> np.ndarray:
        model, data = self.model, self.data
        pin.forwardKinematics(model, data, q)  # the joints that stay as they are
        varied = {self._joint_id[n]: column for column, n in enumerate(joints)}
        needed: set[int] = set()
        for j in riding:
            while j > 0 and j not in needed:
                needed.add(j)
                j = int(model.parents[j])
        placed: dict[int, np.ndarray] = {0: base}
        for j in sorted(needed):  # (a parent's id is below its children's)
            local = (self._placement[j] @ self._motion(j, states[:, varied[j]])
                     if j in varied else data.liMi[j].homogeneous)
            placed[j] = placed[int(model.parents[j])] @ local
        # each link's frame written in place (S x 4 x 4, or one 4 x 4 for all the states
        # where nothing it rides on moves)
        out = np.empty((len(states), len(per_link), 4, 4))
        for column, (j, frame) in enumerate(per_link):
            out[:, column] = placed[j] if frame is None else placed[j] @ frame
        return out

    def _motion(self, j: int, values: np.ndarray) -> np.ndarray:
        """The motion of joint j (S x 4 x 4) at each of `values` (angle or displacement)."""
        kind, axis = self._kind[j]
        out = np.zeros((len(values), 4, 4))
        out[:, 3, 3] = 1.0
        if kind == "prismatic":
            out[:, :3, :3] = np.eye(3)
            out[:, :3, 3] = values[:, None] * axis
            return out
        skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                         [-axis[1], axis[0], 0.0]])  # Rodrigues: I + sin K + (1 - cos) K^2
        out[:, :3, :3] = (np.eye(3) + np.sin(values)[:, None, None] * skew
                          + (1.0 - np.cos(values))[:, None, None] * (skew @ skew))
        return out


def _put_state(q: np.ndarray, slots: list[tuple[int, bool]], row: Sequence[float]) -> None:
    """Write a row of joint values into Pinocchio's configuration q at their slots (a
    continuous joint as its angle's cosine and sine)."""
    for (i, continuous), value in zip(slots, row, strict=True):
        if continuous:
            q[i], q[i + 1] = np.cos(value), np.sin(value)
        else:
            q[i] = value


def _joint_kind(joint) -> tuple[str, np.ndarray]:
    """("revolute" or "prismatic", unit axis in the joint's frame) of a 1-dof joint (a
    continuous joint is revolute: its angle is what the states hold); "other" else."""
    name = joint.shortname()
    axes = {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([0.0, 1.0, 0.0]),
            "Z": np.array([0.0, 0.0, 1.0])}
    if name in ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        return "revolute", np.asarray(joint.extract().axis, dtype=float)
    if name == "JointModelPrismaticUnaligned":
        return "prismatic", np.asarray(joint.extract().axis, dtype=float)
    if name[:-1] in ("JointModelR", "JointModelRUB"):
        return "revolute", axes[name[-1]]
    if name[:-1] == "JointModelP":
        return "prismatic", axes[name[-1]]
    return "other", np.zeros(3)
