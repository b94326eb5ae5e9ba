"""Process modules: what executes motion designators on a robot.

`ProcessModules` is the interface a real robot's drivers would implement; the
simulated set moves the PR2 kinematically in a PyBullet world (as PyCRAM's BulletWorld
does) and carries attached objects along with the gripper.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

from cramlite.motion.ik import tool_frame
from cramlite.world.bodies import Quat, Vec3
from cramlite.world.bullet import p
from cramlite.world.world import World

BasePose = tuple[float, float, float]


class ProcessModules(ABC):
    """Executes atomic motions. Implement this to drive another (or a real) robot."""

    @abstractmethod
    def move_base(self, waypoints: Sequence[BasePose]) -> None:
        """Drive through the waypoints (x, y, yaw) in order."""

    @abstractmethod
    def move_joints(self, joints: dict[str, float]) -> None:
        """Move arm and torso joints to the given angles (radians / metres)."""

    @abstractmethod
    def move_gripper(self, arm: str, state: str) -> None:
        """Open or close a gripper (`state` is "open" or "close")."""

    @abstractmethod
    def attach(self, arm: str, obj: str) -> None:
        """The object now moves with the gripper."""

    @abstractmethod
    def detach(self, arm: str, obj: str) -> None:
        """Let go of the object."""

    @abstractmethod
    def settle(self, seconds: float) -> None:
        """Let the world come to rest (a real robot just waits)."""

    @abstractmethod
    def base_pose(self) -> BasePose: ...

    @abstractmethod
    def joint_positions(self, names: Sequence[str]) -> dict[str, float]: ...

    @abstractmethod
    def object_pose(self, obj: str) -> tuple[Vec3, Quat]:
        """Where an object is (perception on a real robot)."""

    @abstractmethod
    def tool_pose(self, arm: str) -> tuple[Vec3, Quat]:
        """Where a gripper's tool frame is (forward kinematics of the measured joints)."""


GRIPPER_JOINTS = ("gripper_l_finger_joint", "gripper_r_finger_joint",
                  "gripper_l_finger_tip_joint", "gripper_r_finger_tip_joint")
GRIPPER_OPEN, GRIPPER_CLOSED = 0.5, 0.0


class SimulatedProcessModules(ProcessModules):
    """Kinematic execution in a PyBullet `World`."""

    def __init__(self, world: World):
        self.world = world
        self.robot = world.robot
        self.client = world.client
        self._attached: dict[str, tuple[str, tuple[Vec3, Quat], float]] = {}
        for link in range(-1, p.getNumJoints(self.robot.body, physicsClientId=self.client)):
            # the robot moves kinematically; physics steps (settling) must not push it or items
            p.setCollisionFilterGroupMask(self.robot.body, link, 0, 0,
                                          physicsClientId=self.client)

    def move_base(self, waypoints: Sequence[BasePose]) -> None:
        for x, y, yaw in waypoints:
            self.robot.set_base_pose(x, y, yaw)
        self._carry()

    def move_joints(self, joints: dict[str, float]) -> None:
        self.robot.set_joint_positions(joints)
        self._carry()

    def move_gripper(self, arm: str, state: str) -> None:
        value = GRIPPER_OPEN if state == "open" else GRIPPER_CLOSED
        prefix = arm[0]
        self.robot.set_joint_positions({f"{prefix}_{j}": value for j in GRIPPER_JOINTS
                                        if f"{prefix}_{j}" in self.robot.joint_index})

    def attach(self, arm: str, obj: str) -> None:
        body = self.world.objects[obj]
        tool = self.robot.link_pose(tool_frame(arm))
        inv = p.invertTransform(*tool)
        relative = p.multiplyTransforms(*inv, *body.pose())
        mass = p.getDynamicsInfo(body.body, -1, physicsClientId=self.client)[0]
        p.changeDynamics(body.body, -1, mass=0.0, physicsClientId=self.client)  # held: no fall
        self._attached[obj] = (arm, relative, mass)

    def detach(self, arm: str, obj: str) -> None:
        _, _, mass = self._attached.pop(obj)
        body = self.world.objects[obj]
        p.changeDynamics(body.body, -1, mass=mass, physicsClientId=self.client)
        pos, orn = body.pose()
        body.set_pose(pos, orn)  # zero velocities after the mass change

    def settle(self, seconds: float) -> None:
        joints = self.robot.joint_positions()
        self.world.step(seconds)
        self.robot.set_joint_positions(joints)  # undo any sag of the unactuated arms
        self._carry()

    def base_pose(self) -> BasePose:
        return self.robot.base_pose()

    def joint_positions(self, names: Sequence[str]) -> dict[str, float]:
        return self.robot.joint_positions(list(names))

    def object_pose(self, obj: str) -> tuple[Vec3, Quat]:
        return self.world.objects[obj].pose()

    def tool_pose(self, arm: str) -> tuple[Vec3, Quat]:
        return self.robot.link_pose(tool_frame(arm))

    def _carry(self) -> None:
        for obj, (arm, relative, _) in self._attached.items():
            tool = self.robot.link_pose(tool_frame(arm))
            pos, orn = p.multiplyTransforms(*tool, *relative)
            self.world.objects[obj].set_pose(pos, orn)
