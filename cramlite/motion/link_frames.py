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
        self._base_to_root = self._calibrate()

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
        as they stand now); None if some link or joint is not in Pinocchio's model."""
        if self._base_to_root is None or any(n not in self._slot for n in joints) or \
                any(link not in self._link for link in links):
            return None
        pin, model, data = self._pin, self.model, self.data
        q = self._q()
        riding = sorted({self._link[link][0] for link in links})
        column = {j: k for k, j in enumerate(riding)}
        placements = np.array([self._link[link][1] for link in links])  # L x 4 x 4
        which = [column[self._link[link][0]] for link in links]
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
        world = self._base() @ self._base_to_root
        frames = world @ out[:, which] @ placements  # (einsum: four times slower)
        return frames[..., :3, 3], frames[..., :3, :3]
