"""Handles on bodies inside one PyBullet client: the robot and the items.

Every call passes the owning world's client id, so two worlds never share state.
"""

from __future__ import annotations

from dataclasses import dataclass

from cramlite.backends.pybullet.client import p
from cramlite.scene.transforms import Quat, Vec3, quat_yaw, yaw_quat
from cramlite.world.setup import ItemSpec

__all__ = ["Quat", "RobotBody", "Vec3", "WorldObject", "quat_yaw", "yaw_quat"]


@dataclass
class WorldObject:
    """An item in a world. Its frame is the centre of its bottom face (see worlds/items)."""

    name: str
    type: str
    body: int
    client: int
    spec: ItemSpec | None = None
    #: Size (x, y, z) of the upright item in its own frame, measured when it was loaded.
    extents: Vec3 = (0.0, 0.0, 0.0)
    _inertial: tuple[Vec3, Quat] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))

    def __post_init__(self) -> None:
        info = p.getDynamicsInfo(self.body, -1, physicsClientId=self.client)
        self._inertial = (tuple(info[3]), tuple(info[4]))

    @property
    def inertial_frame(self) -> tuple[Vec3, Quat]:
        """The inertial frame in the item's frame (PyBullet places bodies by it)."""
        return self._inertial

    def pose(self) -> tuple[Vec3, Quat]:
        """Position and orientation of the item's frame (PyBullet reports the COM frame)."""
        com_pos, com_orn = p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        inv_pos, inv_orn = p.invertTransform(*self._inertial)
        pos, orn = p.multiplyTransforms(com_pos, com_orn, inv_pos, inv_orn)
        return tuple(pos), tuple(orn)

    def position(self) -> Vec3:
        return self.pose()[0]

    def set_pose(self, position: Vec3, orientation: Quat = (0.0, 0.0, 0.0, 1.0)) -> None:
        pos, orn = p.multiplyTransforms(position, orientation, *self._inertial)
        p.resetBasePositionAndOrientation(self.body, pos, orn, physicsClientId=self.client)
        p.resetBaseVelocity(self.body, (0, 0, 0), (0, 0, 0), physicsClientId=self.client)

    def aabb(self) -> tuple[Vec3, Vec3]:
        lo, hi = p.getAABB(self.body, -1, physicsClientId=self.client)
        return tuple(lo), tuple(hi)

    def is_round(self) -> bool:
        """A single upright cylinder (its footprint does not change with yaw)."""
        shapes = p.getCollisionShapeData(self.body, -1, physicsClientId=self.client)
        return len(shapes) == 1 and shapes[0][2] == p.GEOM_CYLINDER

    def height(self) -> float:
        """Height of the upright item (however it is tilted now, e.g. in a gripper)."""
        return self.extents[2]


class RobotBody:
    """The PR2 in a PyBullet client: base pose, joints and links by name."""

    def __init__(self, body: int, client: int):
        self.body = body
        self.client = client
        self.joint_index: dict[str, int] = {}
        self.link_index: dict[str, int] = {}
        self.joint_limits: dict[str, tuple[float, float]] = {}
        #: Velocity limit of each joint (rad/s or m/s), from the URDF.
        self.velocity_limits: dict[str, float] = {}
        self.prismatic: set[str] = set()
        #: The base pose last set (the base is fixed in PyBullet: only this moves it).
        self._base: tuple[float, float, float] | None = None
        for j in range(p.getNumJoints(body, physicsClientId=client)):
            info = p.getJointInfo(body, j, physicsClientId=client)
            self.link_index[info[12].decode()] = j
            if info[2] != p.JOINT_FIXED:
                name = info[1].decode()
                self.joint_index[name] = j
                self.joint_limits[name] = (info[8], info[9])
                self.velocity_limits[name] = float(info[11])
                if info[2] == p.JOINT_PRISMATIC:
                    self.prismatic.add(name)
        base_name = p.getBodyInfo(body, physicsClientId=client)[0].decode()
        self.link_index[base_name] = -1
        # no default velocity motors: the robot moves kinematically, and those motors cost
        # two thirds of every physics step (shared/PITFALLS.md)
        movable = list(self.joint_index.values())
        p.setJointMotorControlArray(body, movable, p.VELOCITY_CONTROL,
                                    forces=[0.0] * len(movable), physicsClientId=client)

    def is_continuous(self, name: str) -> bool:
        """A revolute joint without limits (PyBullet reports lower 0, upper -1)."""
        lower, upper = self.joint_limits[name]
        return name not in self.prismatic and lower > upper

    def set_base_pose(self, x: float, y: float, yaw: float) -> None:
        """Move the base (skipped when it is there already: a reset recomputes every link,
        and collision checks put the base back and forth)."""
        if (x, y, yaw) == self._base:
            return
        p.resetBasePositionAndOrientation(self.body, (x, y, 0.0), yaw_quat(yaw),
                                          physicsClientId=self.client)
        self._base = (x, y, yaw)

    def base_pose(self) -> tuple[float, float, float]:
        pos, orn = p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        return pos[0], pos[1], quat_yaw(orn)

    def set_joint_positions(self, positions: dict[str, float]) -> None:
        """Set joints by name in one batched call."""
        if positions:
            p.resetJointStatesMultiDof(self.body, [self.joint_index[n] for n in positions],
                                       [[float(v)] for v in positions.values()],
                                       physicsClientId=self.client)

    def joint_positions(self, names: list[str] | None = None) -> dict[str, float]:
        names = list(self.joint_index) if names is None else names
        states = p.getJointStates(self.body, [self.joint_index[n] for n in names],
                                  physicsClientId=self.client)
        return {n: s[0] for n, s in zip(names, states, strict=True)}

    def link_pose(self, link: str) -> tuple[Vec3, Quat]:
        index = self.link_index[link]
        if index == -1:
            pos, orn = p.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
            return tuple(pos), tuple(orn)
        state = p.getLinkState(self.body, index, computeForwardKinematics=True,
                               physicsClientId=self.client)
        return tuple(state[4]), tuple(state[5])
