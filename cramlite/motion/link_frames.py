"""World frames of the robot's links for many joint vectors at once, from Pinocchio.

The broadphase of a motion check needs every moving link's frame in every state of the
motion. Asking PyBullet (reset the joints, then query the links) costs 45-65 us a state;
Pinocchio's forward kinematics of the same URDF costs about a third of that. The frames
are tied to PyBullet's by one calibration (the base's pose in PyBullet against
Pinocchio's root frame), checked on every link when built: if they do not agree, the
caller is told (None) and asks PyBullet as before.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cramlite.world.bodies import yaw_quat
from cramlite.world.bullet import p
from cramlite.world.pr2 import pinocchio_pr2

#: Largest disagreement (m) between PyBullet's and Pinocchio's frames accepted at
#: calibration.
AGREEMENT_M = 1e-5
#: Fewer states than this are placed state by state (Pinocchio's forward kinematics);
#: more, for all states at once (measured: from about 8 states on, that is faster).
FEW_STATES = 8


def _homogeneous(position: Sequence[float], quaternion: Sequence[float]) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = np.array(p.getMatrixFromQuaternion(quaternion)).reshape(3, 3)
    out[:3, 3] = position
    return out


class LinkFrames:
    """Link frames (PyBullet link indices) of a PyBullet robot, by Pinocchio."""

    def __init__(self, robot, client: int):
        import pinocchio as pin

        self._pin = pin
        self.robot = robot
        self.client = client
        self.model = pinocchio_pr2().model
        self.data = self.model.createData()
        model = self.model
        self._slot = {name: (int(model.idx_qs[model.getJointId(name)]),
                             int(model.nqs[model.getJointId(name)]) == 2)
                      for name in robot.joint_index if model.existJointName(name)}
        #: link -> (Pinocchio joint it rides on, the link's frame in that joint's frame)
        self._link: dict[int, tuple[int, np.ndarray]] = {}
        for link in range(p.getNumJoints(robot.body, physicsClientId=client)):
            name = p.getJointInfo(robot.body, link, physicsClientId=client)[12].decode()
            if model.existFrame(name):
                frame = model.frames[model.getFrameId(name)]
                self._link[link] = (int(frame.parentJoint), frame.placement.homogeneous.copy())
        #: Pinocchio joint id of each joint by name; each joint's placement in its
        #: parent's frame and its kind and axis (for `frames`)
        self._joint_id = {name: int(model.getJointId(name)) for name in self._slot}
        self._placement = {j: model.jointPlacements[j].homogeneous.copy()
                           for j in range(1, model.njoints)}
        self._kind = {j: self._joint_kind(model.joints[j]) for j in range(1, model.njoints)}
        self._base_to_root = self._calibrate()

    @staticmethod
    def _joint_kind(joint) -> tuple[str, np.ndarray]:
        """("revolute" or "prismatic", unit axis in the joint's frame) of a 1-dof joint
        (a continuous joint is revolute: its angle is what the states hold)."""
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

    def _q(self) -> np.ndarray:
        """Pinocchio's configuration of the robot as it stands in PyBullet."""
        q = self._pin.neutral(self.model)
        for name, value in self.robot.joint_positions().items():
            if name in self._slot:
                self._set(q, name, value)
        return q

    def _set(self, q: np.ndarray, name: str, value: float) -> None:
        i, continuous = self._slot[name]
        if continuous:
            q[i], q[i + 1] = np.cos(value), np.sin(value)
        else:
            q[i] = value

    def _base(self) -> np.ndarray:
        x, y, yaw = self.robot.base_pose()
        return _homogeneous((x, y, 0.0), yaw_quat(yaw))

    def _calibrate(self) -> np.ndarray | None:
        """Pinocchio's root frame in the frame of the base pose PyBullet reports, if every
        link agrees with it; None otherwise."""
        if not self._link:
            return None
        self._pin.forwardKinematics(self.model, self.data, self._q())
        links = sorted(self._link)
        states = p.getLinkStates(self.robot.body, links, computeForwardKinematics=True,
                                 physicsClientId=self.client)
        base_inv = np.linalg.inv(self._base())
        mine = [self._local(link) for link in links]
        first = _homogeneous(states[0][4], states[0][5])
        base_to_root = base_inv @ first @ np.linalg.inv(mine[0])
        world_to_root = self._base() @ base_to_root
        for state, local in zip(states, mine, strict=True):
            if np.abs((world_to_root @ local)[:3, 3] - state[4]).max() > AGREEMENT_M:
                return None
        return base_to_root

    def _local(self, link: int) -> np.ndarray:
        joint, placement = self._link[link]
        return self.data.oMi[joint].homogeneous @ placement

    @property
    def usable(self) -> bool:
        return self._base_to_root is not None

    def frames(self, joints: Sequence[str], states: np.ndarray, links: Sequence[int],
               ) -> tuple[np.ndarray, np.ndarray] | None:
        """Positions (S x links x 3) and rotation matrices (S x links x 3 x 3) of `links`
        with the robot's `joints` at each row of `states` (its other joints and its base
        as they stand now); None if some link or joint is not in Pinocchio's model.

        The kinematic chain is composed for all states at once (one matrix product per
        joint, over S states): the joints that do not change between states are placed
        once, by Pinocchio, where the robot stands now."""
        if self._base_to_root is None or any(n not in self._slot for n in joints) or \
                any(link not in self._link for link in links):
            return None
        states = np.asarray(states, dtype=float)
        riding = sorted({self._link[link][0] for link in links})
        if len(states) < FEW_STATES:
            out = self._each_state(joints, states, riding)
        else:
            out = self._all_states(joints, states, riding)
            if out is None:
                return None
        column = {j: k for k, j in enumerate(riding)}
        placements = np.array([self._link[link][1] for link in links])  # L x 4 x 4
        frames = out[:, [column[self._link[link][0]] for link in links]] @ placements
        return frames[..., :3, 3], frames[..., :3, :3]

    def _each_state(self, joints: Sequence[str], states: np.ndarray, riding: list[int],
                    ) -> np.ndarray:
        """The world frames (S x riding x 4 x 4) of joints `riding`, by Pinocchio's
        forward kinematics state by state."""
        pin, model, data = self._pin, self.model, self.data
        q = self._q()
        slots = [self._slot[n] for n in joints]
        out = np.empty((len(states), len(riding), 4, 4))
        for s, values in enumerate(states):
            for (i, continuous), value in zip(slots, values, strict=True):
                if continuous:
                    q[i], q[i + 1] = np.cos(value), np.sin(value)
                else:
                    q[i] = value
            pin.forwardKinematics(model, data, q)
            for k, j in enumerate(riding):
                out[s, k] = data.oMi[j].homogeneous
        return self._base() @ self._base_to_root @ out

    def _all_states(self, joints: Sequence[str], states: np.ndarray, riding: list[int],
                    ) -> np.ndarray | None:
        """As `_each_state`, the chain composed for all states at once (None if a joint
        that moves is not one Pinocchio turns or slides about an axis)."""
        pin, model, data = self._pin, self.model, self.data
        pin.forwardKinematics(model, data, self._q())  # the joints that stay as they are
        varied = {self._joint_id[n]: column for column, n in enumerate(joints)}
        if any(self._kind[j][0] == "other" for j in varied):  # (not a 1-dof joint)
            return None
        needed: set[int] = set()
        for j in riding:
            while j > 0 and j not in needed:
                needed.add(j)
                j = int(model.parents[j])
        placed = {0: self._base() @ self._base_to_root}  # j -> 4x4 or S x 4 x 4
        for j in sorted(needed):  # (a parent's id is below its children's)
            local = (self._placement[j] @ self._motion(j, states[:, varied[j]])
                     if j in varied else data.liMi[j].homogeneous)
            placed[j] = placed[int(model.parents[j])] @ local
        return np.stack([np.broadcast_to(placed[j], (len(states), 4, 4)) for j in riding],
                        axis=1)

    def _motion(self, j: int, values: np.ndarray) -> np.ndarray:
        """The motion of joint j (S x 4 x 4) at each of `values` (angle or displacement)."""
        kind, axis = self._kind[j]
        out = np.zeros((len(values), 4, 4))
        out[:, 3, 3] = 1.0
        if kind == "prismatic":
            out[:, :3, :3] = np.eye(3)
            out[:, :3, 3] = values[:, None] * axis
            return out
        # Rodrigues: I + sin(a) K + (1 - cos(a)) K^2
        skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                         [-axis[1], axis[0], 0.0]])
        out[:, :3, :3] = (np.eye(3) + np.sin(values)[:, None, None] * skew
                          + (1.0 - np.cos(values))[:, None, None] * (skew @ skew))
        return out
