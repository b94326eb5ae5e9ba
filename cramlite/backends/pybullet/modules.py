"""The PyBullet backend's process modules: kinematic execution in a PyBullet `World`.

The robot moves through every state of a trajectory (as PyCRAM's BulletWorld does, but
never jumping to a goal) and carries attached objects along with the gripper; a drawer
or door follows the hand; a released item settles under physics (`settle`).
"""

from __future__ import annotations

from collections.abc import Sequence

from cramlite.backends.base import (
    REST_ANGULAR_RAD_S,
    REST_LINEAR_M_S,
    SETTLE_CHUNK_STEPS,
    BasePose,
    PhysicsRecord,
    ProcessModules,
    StateObserver,
)
from cramlite.backends.pybullet.bodies import Quat, Vec3
from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import TIME_STEP_S, World
from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.scene.scene import tool_frame


class SimulatedProcessModules(ProcessModules):
    """Kinematic execution in a PyBullet `World`, state by state."""

    def __init__(self, world: World):
        self.world = world
        self.robot = world.robot
        self.client = world.client
        self._attached: dict[str, tuple[str, tuple[Vec3, Quat], float]] = {}
        self.physics = PhysicsRecord()
        for link in range(-1, p.getNumJoints(self.robot.body, physicsClientId=self.client)):
            # the robot moves kinematically; physics steps (settling) must not push it or items
            p.setCollisionFilterGroupMask(self.robot.body, link, 0, 0,
                                          physicsClientId=self.client)

    def release_all(self) -> None:
        """Let go of everything (a new trial starts with empty hands)."""
        for obj, (arm, _, _) in list(self._attached.items()):
            self.detach(arm, obj)

    @property
    def skips_unwatched_states(self) -> bool:  # (the GUI shows every state)
        return not self.world.gui

    def _states(self, count: int, on_state: StateObserver) -> range:
        """The states to put the world in: every one while something watches (a trace, the
        GUI), else the last (the robot moves kinematically and nothing in this world acts
        on the states between: replaying them would only cost time)."""
        return range(count) if on_state is not None or self.world.gui else range(count - 1,
                                                                                  count)

    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        for i in self._states(len(trajectory.poses), on_state):
            x, y, yaw = trajectory.poses[i]
            self.robot.set_base_pose(float(x), float(y), float(yaw))
            self._carry()
            if on_state is not None:
                on_state(i)

    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        indices = [self.robot.joint_index[n] for n in trajectory.names]
        held = set(self._attached)
        for i in self._states(len(trajectory.positions), on_state):
            state = trajectory.positions[i]
            p.resetJointStatesMultiDof(self.robot.body, indices, [[float(v)] for v in state],
                                       physicsClientId=self.client)
            for joint, values in trajectory.world.items():  # the handle pulls the drawer
                self.world.set_world_joint(joint, float(values[i]), exclude=held)
            self._carry()
            if on_state is not None:
                on_state(i)

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

    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        """Step physics until `objects` are at rest (or `seconds` have passed)."""
        joints = self.robot.joint_positions()
        drawers = self.world.world_joint_positions()
        bodies = [self.world.objects[n].body for n in objects]
        steps = max(1, round(seconds / TIME_STEP_S))
        done, resting = 0, 0
        while done < steps:
            chunk = min(SETTLE_CHUNK_STEPS, steps - done)
            for _ in range(chunk):
                p.stepSimulation(physicsClientId=self.client)
            done += chunk
            for body in bodies:  # (contact distance < 0: penetration)
                for point in p.getContactPoints(bodyA=body, physicsClientId=self.client):
                    self.physics.deepest_contact_m = max(self.physics.deepest_contact_m,
                                                         -point[8])
            resting = resting + 1 if bodies and all(_at_rest(b, self.client)
                                                    for b in bodies) else 0
            if resting >= 2:  # at rest over two checks, not at the top of a bounce
                break
        self.physics.steps += done
        self.robot.set_joint_positions(joints)  # undo any sag of the unactuated joints
        for name, value in drawers.items():  # and any give of the drawers and doors
            p.resetJointState(self.world.environment, self.world.world_joints[name], value,
                              physicsClientId=self.client)
        self._carry()

    def simulator_report(self) -> dict[str, float]:
        return self.physics.report()

    def base_pose(self) -> BasePose:
        return self.robot.base_pose()

    def joint_positions(self, names: Sequence[str]) -> dict[str, float]:
        return self.robot.joint_positions(list(names))

    def world_joint_positions(self) -> dict[str, float]:
        return self.world.world_joint_positions()

    def object_pose(self, obj: str) -> tuple[Vec3, Quat]:
        """Where an item is, to the micrometre (PyBullet keeps bodies' poses in single
        precision: what it reports beyond that is noise of its own, not the world's)."""
        (x, y, z), orientation = self.world.objects[obj].pose()
        return (round(x, 6), round(y, 6), round(z, 6)), orientation

    def tool_pose(self, arm: str) -> tuple[Vec3, Quat]:
        return self.robot.link_pose(tool_frame(arm))

    def _carry(self) -> None:
        for obj, (arm, relative, _) in self._attached.items():
            tool = self.robot.link_pose(tool_frame(arm))
            pos, orn = p.multiplyTransforms(*tool, *relative)
            self.world.objects[obj].set_pose(pos, orn)


def _at_rest(body: int, client: int) -> bool:
    linear, angular = p.getBaseVelocity(body, physicsClientId=client)
    return (sum(v * v for v in linear) ** 0.5 < REST_LINEAR_M_S
            and sum(v * v for v in angular) ** 0.5 < REST_ANGULAR_RAD_S)
