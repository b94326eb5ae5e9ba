"""The PyBullet backend's `World`: one PyBullet client with a kitchen, the PR2 and items.

A world owns its client (DIRECT by default, GUI on request) and is closed with it;
nothing is kept at module level, so any number of worlds can live in one process. It
executes (process modules move its bodies) and is observed; planning never asks it
anything: the planning scene (`cramlite.scene`) is the planner's model of the world.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cramlite.backends.pybullet.bodies import RobotBody, Vec3, WorldObject, yaw_quat
from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.display import display_problem
from cramlite.backends.pybullet.quiet import c_stdout_silenced
from cramlite.errors import SetupError
from cramlite.world.containers import Container, load_containers
from cramlite.world.pr2 import pr2_urdf_path
from cramlite.world.setup import Setup

TIME_STEP_S = 1.0 / 240.0
GRAVITY = -9.81
@dataclass(frozen=True)
class Snapshot:
    """Poses of everything a plan changes, to reset a world cheaply between trials."""

    base: tuple[float, float, float]
    joints: dict[str, float]
    objects: dict[str, tuple[Vec3, tuple[float, float, float, float]]]
    world_joints: dict[str, float] = field(default_factory=dict)


class World:
    """A PyBullet world. Use as a context manager or call `close()`."""

    def __init__(self, gui: bool = False):
        problem = display_problem() if gui else None
        if problem:  # (PyBullet would end the whole process from C code)
            raise RuntimeError(problem)
        with c_stdout_silenced():
            self.client = p.connect(p.GUI if gui else p.DIRECT)
        if self.client < 0:
            raise RuntimeError("PyBullet could not connect (a GUI needs a display)")
        self.gui = gui
        p.setGravity(0, 0, GRAVITY, physicsClientId=self.client)
        p.setTimeStep(TIME_STEP_S, physicsClientId=self.client)
        self.environment: int | None = None
        self.environment_links: dict[str, int] = {}
        #: The environment's movable joints (drawers, doors), by name.
        self.world_joints: dict[str, int] = {}
        self.containers: dict[str, Container] = {}
        self.robot: RobotBody | None = None
        self.objects: dict[str, WorldObject] = {}
        self.setup: Setup | None = None

    # -- lifetime -------------------------------------------------------------------
    def close(self) -> None:
        if self.client is not None and self.client >= 0:
            p.disconnect(physicsClientId=self.client)
            self.client = -1

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # -- loading --------------------------------------------------------------------
    @classmethod
    def from_setup(cls, setup: Setup, gui: bool = False) -> World:
        """A new world with the setup's environment, the PR2 at its start and the items."""
        world = cls(gui=gui)
        try:
            world.load_setup(setup)
        except BaseException:
            world.close()
            raise
        return world

    def load_setup(self, setup: Setup) -> None:
        self.setup = setup
        self.load_environment(setup.world_urdf)
        self.load_robot()
        self.robot.set_base_pose(setup.robot_start.x, setup.robot_start.y, setup.robot_start.yaw)
        for i, spec in enumerate(setup.items):
            try:
                obj = self.add_object(spec.name, spec.type, spec.urdf)
            except SetupError as exc:
                raise SetupError(f"{spec.urdf}: {exc.detail}", source=str(setup.source),
                                 field=f"items[{i}].type") from None
            obj.spec = spec
            obj.set_pose(spec.pose.xyz, yaw_quat(spec.pose.yaw))

    def _load_urdf(self, path: Path, fixed: bool, flags: int = 0) -> int:
        with c_stdout_silenced():
            body = p.loadURDF(str(path), useFixedBase=fixed, flags=flags,
                              physicsClientId=self.client)
        if body < 0:
            raise SetupError("PyBullet could not load this URDF", source=str(path))
        return body

    def load_environment(self, urdf: Path) -> None:
        self.environment = self._load_urdf(urdf, fixed=True)
        base = p.getBodyInfo(self.environment, physicsClientId=self.client)[0].decode()
        self.environment_links = {base: -1}
        self.world_joints = {}
        for j in range(p.getNumJoints(self.environment, physicsClientId=self.client)):
            info = p.getJointInfo(self.environment, j, physicsClientId=self.client)
            self.environment_links[info[12].decode()] = j
            if info[2] != p.JOINT_FIXED:
                self.world_joints[info[1].decode()] = j
                self._hold_world_joint(j, 0.0)
        self.containers = {name: c for name, c in load_containers(urdf).items()
                           if c.inside_link in self.environment_links}

    # -- the world's own joints (drawers, doors) ------------------------------------------
    def _hold_world_joint(self, index: int, value: float) -> None:
        """Physics steps keep the joint where it was put (the robot moves it kinematically)."""
        p.setJointMotorControl2(self.environment, index, p.POSITION_CONTROL,
                                targetPosition=value, force=1e4, physicsClientId=self.client)

    def world_joint_positions(self) -> dict[str, float]:
        return {name: p.getJointState(self.environment, index, physicsClientId=self.client)[0]
                for name, index in self.world_joints.items()}

    def link_frame(self, link: str) -> tuple[Vec3, tuple[float, float, float, float]]:
        """Pose of an environment link's frame in the world."""
        index = self.environment_links[link]
        if index == -1:
            pos, orn = p.getBasePositionAndOrientation(self.environment,
                                                       physicsClientId=self.client)
        else:
            state = p.getLinkState(self.environment, index, computeForwardKinematics=True,
                                   physicsClientId=self.client)
            pos, orn = state[4], state[5]
        return tuple(pos), tuple(orn)

    def container_of_joint(self, joint: str) -> Container | None:
        return next((c for c in self.containers.values() if c.joint == joint), None)

    def items_inside(self, container: Container, exclude: set[str] | None = None) -> list[str]:
        """Items standing inside a container now (by where they are)."""
        frame = p.invertTransform(*self.link_frame(container.inside_link))
        out = []
        for name, obj in self.objects.items():
            if exclude and name in exclude:
                continue
            local, _ = p.multiplyTransforms(*frame, *obj.pose())
            (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
            if x0 <= local[0] <= x1 and y0 <= local[1] <= y1 and z0 - 0.02 <= local[2] <= z1:
                out.append(name)
        return out

    def set_world_joint(self, name: str, value: float, exclude: set[str] | None = None) -> None:
        """Move a drawer or door; items inside a drawer move with it (but `exclude`)."""
        index = self.world_joints[name]
        container = self.container_of_joint(name)
        carried = []
        if container is not None and container.inside_link == container.link:
            frame = self.link_frame(container.link)
            inverse = p.invertTransform(*frame)
            for item in self.items_inside(container, exclude):
                carried.append((item, p.multiplyTransforms(*inverse,
                                                           *self.objects[item].pose())))
        p.resetJointState(self.environment, index, value, physicsClientId=self.client)
        self._hold_world_joint(index, value)
        if carried:
            frame = self.link_frame(container.link)
            for item, relative in carried:
                self.objects[item].set_pose(*p.multiplyTransforms(*frame, *relative))

    def set_world_joints(self, values: dict[str, float]) -> None:
        for name, value in values.items():
            self.set_world_joint(name, value)

    def load_robot(self) -> RobotBody:
        body = self._load_urdf(pr2_urdf_path(), fixed=True)
        self.robot = RobotBody(body, self.client)
        return self.robot

    def add_object(self, name: str, type_: str, urdf: Path) -> WorldObject:
        # real cylinders (PyBullet would otherwise turn them into meshes)
        body = self._load_urdf(urdf, fixed=False, flags=p.URDF_USE_IMPLICIT_CYLINDER)
        lo, hi = p.getAABB(body, -1, physicsClientId=self.client)  # upright, at the origin
        obj = WorldObject(name=name, type=type_, body=body, client=self.client,
                          extents=(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]))
        self.objects[name] = obj
        return obj

    # -- queries --------------------------------------------------------------------
    def penetration(self, body_a: int, body_b: int, link_b: int | None = None) -> float:
        """Deepest penetration (m, >= 0) between two bodies; 0 when they do not overlap."""
        kwargs = {} if link_b is None else {"linkIndexB": link_b}
        points = p.getClosestPoints(body_a, body_b, 0.0, physicsClientId=self.client, **kwargs)
        return max((-pt[8] for pt in points if pt[8] < 0), default=0.0)

    def body_name(self, body: int) -> str:
        if body == self.environment:
            return "the environment"
        if self.robot is not None and body == self.robot.body:
            return "the robot"
        for obj in self.objects.values():
            if obj.body == body:
                return repr(obj.name)
        return f"body {body}"

    # -- simulation -----------------------------------------------------------------
    def step(self, seconds: float) -> None:
        for _ in range(max(1, round(seconds / TIME_STEP_S))):
            p.stepSimulation(physicsClientId=self.client)

    def snapshot(self) -> Snapshot:
        base = self.robot.base_pose() if self.robot else (0.0, 0.0, 0.0)
        joints = self.robot.joint_positions() if self.robot else {}
        objects = {name: obj.pose() for name, obj in self.objects.items()}
        return Snapshot(base=base, joints=joints, objects=objects,
                        world_joints=self.world_joint_positions())

    def restore(self, snap: Snapshot) -> None:
        if self.robot:
            self.robot.set_base_pose(*snap.base)
            self.robot.set_joint_positions(snap.joints)
        for name, value in snap.world_joints.items():
            index = self.world_joints[name]
            p.resetJointState(self.environment, index, value, physicsClientId=self.client)
            self._hold_world_joint(index, value)
        for name, (pos, orn) in snap.objects.items():
            self.objects[name].set_pose(pos, orn)
