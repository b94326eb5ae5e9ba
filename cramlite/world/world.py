"""The `World`: one PyBullet client with a kitchen, the PR2 and items.

A world owns its client (DIRECT by default, GUI on request) and is closed with it;
nothing is kept at module level, so any number of worlds can live in one process.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.errors import SetupError
from cramlite.world.bodies import RobotBody, Vec3, WorldObject, quat_yaw, yaw_quat
from cramlite.world.bullet import p
from cramlite.world.containers import Container, containers_path, load_containers
from cramlite.world.pr2 import pr2_urdf_path
from cramlite.world.quiet import c_stdout_silenced
from cramlite.world.setup import Setup

TIME_STEP_S = 1.0 / 240.0
GRAVITY = -9.81
#: Penetration deeper than this between an item and another body is "inside" it.
PENETRATION_TOLERANCE_M = 0.005
#: An item must start within this height of its surface's top.
SURFACE_HEIGHT_TOLERANCE_M = 0.01
#: The link of a world URDF the robot stands on (not a surface for items).
FLOOR_LINK = "floor"
#: A link turned further than this from square to the axes (|sin 2 yaw|, about 0.6
#: degrees) is drawn on 2D maps by its outline rather than its axis-aligned bounds.
TURNED_SIN = 0.02


@dataclass(frozen=True)
class Surface:
    """A horizontal support (a link of the world URDF): its top and its xy extent."""

    name: str
    x_min: float
    x_max: float
    y_min: float
    y_max: float
    top_z: float

    def contains_xy(self, x: float, y: float, margin: float = 0.0) -> bool:
        return (self.x_min + margin <= x <= self.x_max - margin
                and self.y_min + margin <= y <= self.y_max - margin)


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
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            # PyBullet would exit the whole process from C code
            raise RuntimeError("the GUI needs a display, and DISPLAY is not set")
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
        #: Data derived from this world's fixed geometry (occupancy maps, the collision
        #: checker), computed once by the layers that need it and kept with the world.
        self.cache: dict[Any, Any] = {}

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
        self.check_setup_geometry(setup)

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
        self.containers = load_containers(urdf)
        for container in self.containers.values():
            for link in (container.link, container.handle, container.inside_link):
                if link not in self.environment_links:
                    raise SetupError(f"container {container.name!r}: the world has no link "
                                     f"{link!r}", source=str(containers_path(urdf)))
            if container.joint not in self.world_joints:
                raise SetupError(f"container {container.name!r}: the world has no movable "
                                 f"joint {container.joint!r}", source=str(containers_path(urdf)))

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

    @contextlib.contextmanager
    def joint_at(self, joint: str, value: float) -> Iterator[None]:
        """Put one world joint at a value for a look (nothing else moves), then back."""
        index = self.world_joints[joint]
        before = p.getJointState(self.environment, index, physicsClientId=self.client)[0]
        p.resetJointState(self.environment, index, value, physicsClientId=self.client)
        try:
            yield
        finally:
            p.resetJointState(self.environment, index, before, physicsClientId=self.client)

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
    def surface(self, name: str) -> Surface:
        if name not in self.environment_links:
            raise KeyError(name)
        lo, hi = self.link_bounds(self.environment_links[name])
        return Surface(name, lo[0], hi[0], lo[1], hi[1], hi[2])

    def link_bounds(self, index: int) -> tuple[Vec3, Vec3]:
        """Exact bounds of an environment link: its box geometry where it is a box
        (PyBullet's AABB is inflated by the collision margin), else the AABB."""
        shapes = p.getCollisionShapeData(self.environment, index, physicsClientId=self.client)
        if len(shapes) == 1 and shapes[0][2] == p.GEOM_BOX:
            if index == -1:
                pos, orn = p.getBasePositionAndOrientation(self.environment,
                                                           physicsClientId=self.client)
            else:
                state = p.getLinkState(self.environment, index, physicsClientId=self.client)
                pos, orn = state[4], state[5]
            centre, rotation = p.multiplyTransforms(pos, orn, shapes[0][5], shapes[0][6])
            matrix = p.getMatrixFromQuaternion(rotation)  # a turned box (a door): its span
            half = [d / 2 for d in shapes[0][3]]
            span = [sum(abs(matrix[3 * r + c]) * half[c] for c in range(3)) for r in range(3)]
            return (tuple(c - h for c, h in zip(centre, span, strict=True)),
                    tuple(c + h for c, h in zip(centre, span, strict=True)))
        lo, hi = p.getAABB(self.environment, index, physicsClientId=self.client)
        return tuple(lo), tuple(hi)

    def link_outlines(self, index: int) -> list[np.ndarray] | None:
        """The xy corners (as seen from above) of each box of a turned environment link (a
        door swung open), where its axis-aligned bounds would cover far more than it does;
        None for a link that stands square to the axes or is not made of boxes."""
        boxes = self._turned_boxes(index)
        if boxes is None:
            return None
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                            for sz in (-1, 1)])
        return [((corners * half) @ matrix.T + centre)[:, :2]
                for centre, matrix, half in boxes]

    def turned_box(self, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(centre, rotation whose columns are its axes, half extents) of an environment
        link made of one box and turned about the vertical (a door swung open), whose
        axis-aligned bounds cover far more than it does; None otherwise."""
        boxes = self._turned_boxes(index)
        return boxes[0] if boxes is not None and len(boxes) == 1 else None

    def _turned_boxes(self, index: int,
                      ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]] | None:
        """(centre, rotation, half extents) of each box of an environment link made of
        boxes and turned about the vertical; None for any other link."""
        shapes = p.getCollisionShapeData(self.environment, index, physicsClientId=self.client)
        if index < 0 or not shapes or any(shape[2] != p.GEOM_BOX for shape in shapes):
            return None
        state = p.getLinkState(self.environment, index, physicsClientId=self.client)
        if abs(math.sin(2 * quat_yaw(state[5]))) < TURNED_SIN:
            return None
        out = []
        for shape in shapes:
            centre, rotation = p.multiplyTransforms(state[4], state[5], shape[5], shape[6])
            out.append((np.asarray(centre),
                        np.array(p.getMatrixFromQuaternion(rotation)).reshape(3, 3),
                        np.asarray(shape[3]) / 2))
        return out

    def moving_environment_links(self) -> list[tuple[str, int]]:
        """(name, index) of the environment links with a shape that a drawer's or door's
        joint moves."""
        return self._environment_links_by_motion()[1]

    def environment_footprints(self) -> list[tuple[str, Vec3, Vec3, list[np.ndarray] | None]]:
        """`environment_boxes` with the outlines of the turned links (see `link_outlines`):
        what 2D maps are drawn from."""
        static, moving = self._environment_links_by_motion()
        return [(name, lo, hi, None) for name, _, lo, hi in static] + \
            [(name, *self.link_bounds(index), self.link_outlines(index))
             for name, index in moving]

    def environment_boxes(self) -> list[tuple[str, Vec3, Vec3]]:
        """Axis-aligned bounds of every environment link (for 2D maps of fixed geometry)."""
        return [(name, lo, hi) for name, _, lo, hi in self.environment_link_boxes()]

    def environment_link_boxes(self) -> list[tuple[str, int, Vec3, Vec3]]:
        """(name, link index, bounds) of every environment link with a shape; the links
        that never move are measured once, those on a drawer or door every time."""
        static, moving = self._environment_links_by_motion()
        return static + [(name, index, *self.link_bounds(index)) for name, index in moving]

    def links_moved_by(self, joint: str) -> frozenset[int]:
        """The environment links (with a shape or not) that a drawer's or door's joint
        moves: its own link and every link below it."""
        key = ("links moved by", joint)
        if key not in self.cache:
            root = self.world_joints[joint]
            parents = {j: info[16] for j, info in self._environment_joints().items()}
            moved = set()
            for link in parents:
                j = link
                while j >= 0 and j != root:
                    j = parents[j]
                if j == root:
                    moved.add(link)
            self.cache[key] = frozenset(moved)
        return self.cache[key]

    def _environment_joints(self) -> dict[int, tuple]:
        """PyBullet's joint info of every environment joint (its child link's index)."""
        key = "environment joints"
        if key not in self.cache:
            self.cache[key] = {j: p.getJointInfo(self.environment, j,
                                                 physicsClientId=self.client)
                               for j in range(p.getNumJoints(self.environment,
                                                             physicsClientId=self.client))}
        return self.cache[key]

    def _environment_links_by_motion(self) -> tuple[list[tuple[str, int, Vec3, Vec3]],
                                                    list[tuple[str, int]]]:
        """The environment links with a shape: those that never move with their bounds
        (measured once), and those on a drawer or door (name, index)."""
        key = "environment link boxes"
        if key not in self.cache:
            static, moving = [], []
            parents = self._environment_joints()
            for name, index in self.environment_links.items():
                if not p.getCollisionShapeData(self.environment, index,
                                               physicsClientId=self.client):
                    continue
                j, moves = index, False
                while j >= 0:
                    moves |= parents[j][2] != p.JOINT_FIXED
                    j = parents[j][16]
                if moves:
                    moving.append((name, index))
                else:
                    static.append((name, index, *self.link_bounds(index)))
            self.cache[key] = (static, moving)
        return self.cache[key]

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

    def _check_in_container(self, spec, src: str, where: str) -> None:
        """An item `in:` a container names one of the world's and fits inside it."""
        container = self.containers.get(spec.container)
        if container is None:
            raise SetupError(f"unknown container {spec.container!r}; expected one of "
                             f"{', '.join(self.containers) or 'none (this world has none)'}",
                             source=src, field=f"{where}.in")
        local, _ = p.multiplyTransforms(*p.invertTransform(
            *self.link_frame(container.inside_link)), spec.pose.xyz, (0, 0, 0, 1))
        ex, ey, ez = self.objects[spec.name].extents
        c, s = abs(math.cos(spec.pose.yaw)), abs(math.sin(spec.pose.yaw))
        half_x, half_y = (c * ex + s * ey) / 2, (s * ex + c * ey) / 2
        if not container.fits(tuple(local), half_x, half_y, ez):
            (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
            bottom = p.multiplyTransforms(*self.link_frame(container.inside_link),
                                          (0, 0, z0), (0, 0, 0, 1))[0][2]
            raise SetupError(
                f"item {spec.name!r} ({ex:.2f} x {ey:.2f} x {ez:.2f} m) at "
                f"{list(spec.pose.xyz)} does not fit in {container.name!r}; expected it "
                f"standing on its bottom (z = {bottom:.2f}), inside {x1 - x0:.2f} x "
                f"{y1 - y0:.2f} m and at most {z1 - z0:.2f} m tall",
                source=src, field=f"{where}.pose")

    def check_setup_geometry(self, setup: Setup) -> None:
        """Refuse a scene a trial could not start from: every item stands on its surface
        and starts inside nothing else; every target rests on the top of a surface, free
        of the furniture and of the other targets; the robot (arms parked) stands on the
        kitchen floor, inside no furniture and no item."""
        src = str(setup.source)

        def fail(fld: str, message: str) -> SetupError:
            return SetupError(message, source=src, field=fld)

        surfaces = [n for n in self.environment_links if n != FLOOR_LINK]
        for i, spec in enumerate(setup.items):
            where = f"items[{i}]"
            if spec.container is not None:
                self._check_in_container(spec, src, where)
                continue
            if spec.surface not in self.environment_links:
                raise fail(f"{where}.surface", f"unknown surface {spec.surface!r}; expected "
                                               f"one of {', '.join(surfaces)}")
            surf = self.surface(spec.surface)
            if (not surf.contains_xy(spec.pose.x, spec.pose.y)
                    or abs(spec.pose.z - surf.top_z) > SURFACE_HEIGHT_TOLERANCE_M):
                raise fail(f"{where}.pose",
                           f"item {spec.name!r} at {list(spec.pose.xyz)} is not on "
                           f"{spec.surface!r}; expected x in [{surf.x_min:.2f}, "
                           f"{surf.x_max:.2f}], y in [{surf.y_min:.2f}, {surf.y_max:.2f}], "
                           f"z = {surf.top_z:.2f}")
            if self._surface_under(spec.target) is None:
                raise fail(f"{where}.target",
                           f"target of {spec.name!r} at {list(spec.target.xyz)} rests on no "
                           f"surface (in the air, off the edge or below the floor); expected "
                           f"z = the top of one of {', '.join(surfaces)} under it")
        self._check_robot_start(setup, fail)
        p.performCollisionDetection(physicsClientId=self.client)
        bodies = [self.environment, self.robot.body, *(o.body for o in self.objects.values())]
        for i, spec in enumerate(setup.items):
            obj = self.objects[spec.name]
            for other in bodies:
                if other == obj.body:
                    continue
                depth = self.penetration(obj.body, other)
                if depth > PENETRATION_TOLERANCE_M:
                    raise fail(f"items[{i}].pose",
                               f"item {spec.name!r} starts inside {self.body_name(other)} "
                               f"(overlap {depth * 100:.1f} cm); expected a free spot")
        self._check_targets(setup, fail)

    def _surface_under(self, pose: Any) -> Surface | None:
        """The surface (not the floor) whose top the pose rests on, if any."""
        for name in self.environment_links:
            if name == FLOOR_LINK:
                continue
            surf = self.surface(name)
            if surf.contains_xy(pose.x, pose.y) and \
                    abs(pose.z - surf.top_z) <= SURFACE_HEIGHT_TOLERANCE_M:
                return surf
        return None

    def _check_robot_start(self, setup: Setup, fail) -> None:
        from cramlite.world.pr2 import PARK_JOINTS

        start = setup.robot_start
        saved = self.robot.joint_positions()
        self.robot.set_joint_positions({k: v for arm in PARK_JOINTS.values()
                                        for k, v in arm.items()})
        try:
            lo, hi = p.getAABB(self.robot.body, -1, physicsClientId=self.client)
            for j in range(p.getNumJoints(self.robot.body, physicsClientId=self.client)):
                a, b = p.getAABB(self.robot.body, j, physicsClientId=self.client)
                lo = [min(x, y) for x, y in zip(lo, a, strict=True)]
                hi = [max(x, y) for x, y in zip(hi, b, strict=True)]
            if FLOOR_LINK in self.environment_links:
                floor = self.surface(FLOOR_LINK)
                if not (floor.contains_xy(lo[0], lo[1]) and floor.contains_xy(hi[0], hi[1])):
                    raise fail("robot.start",
                               f"the robot at ({start.x:g}, {start.y:g}) is not on the floor "
                               f"of the kitchen; expected x in [{floor.x_min:.2f}, "
                               f"{floor.x_max:.2f}], y in [{floor.y_min:.2f}, "
                               f"{floor.y_max:.2f}] with room for the robot")
            p.performCollisionDetection(physicsClientId=self.client)
            for name, index in self.environment_links.items():
                if name == FLOOR_LINK:
                    continue
                depth = self.penetration(self.robot.body, self.environment, index)
                if depth > PENETRATION_TOLERANCE_M:
                    raise fail("robot.start",
                               f"the robot at ({start.x:g}, {start.y:g}) starts inside "
                               f"{name!r} (overlap {depth * 100:.1f} cm); expected a free "
                               "spot on the floor")
            for i, spec in enumerate(setup.items):
                depth = self.penetration(self.robot.body, self.objects[spec.name].body)
                if depth > PENETRATION_TOLERANCE_M:
                    raise fail("robot.start",
                               f"the robot at ({start.x:g}, {start.y:g}) starts inside item "
                               f"{spec.name!r} (items[{i}]); expected a free spot")
        finally:
            self.robot.set_joint_positions(saved)

    def _check_targets(self, setup: Setup, fail) -> None:
        """Put every item at its target, check the targets are free, put them back."""
        saved = {name: obj.pose() for name, obj in self.objects.items()}
        try:
            for spec in setup.items:
                self.objects[spec.name].set_pose(spec.target.xyz, yaw_quat(spec.target.yaw))
            p.performCollisionDetection(physicsClientId=self.client)
            for i, spec in enumerate(setup.items):
                body = self.objects[spec.name].body
                depth = self.penetration(body, self.environment)
                if depth > PENETRATION_TOLERANCE_M:
                    raise fail(f"items[{i}].target",
                               f"target of {spec.name!r} at {list(spec.target.xyz)} is inside "
                               f"the furniture (overlap {depth * 100:.1f} cm); expected a "
                               "free spot on a surface")
                for j, other in enumerate(setup.items[:i]):
                    depth = self.penetration(body, self.objects[other.name].body)
                    if depth > PENETRATION_TOLERANCE_M:
                        raise fail(f"items[{i}].target",
                                   f"target of {spec.name!r} overlaps the target of "
                                   f"{other.name!r} (items[{j}]) by {depth * 100:.1f} cm; "
                                   "expected a spot of its own")
        finally:
            for name, (pos, orn) in saved.items():
                self.objects[name].set_pose(pos, orn)

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
