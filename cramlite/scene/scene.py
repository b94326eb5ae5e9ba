"""The planning scene: what the planner believes about the robot, the kitchen and the items.

A `PlanningScene` holds the models (robot, kitchen, items: `scene.models`) and a belief:
where the base stands, the robot's joints, the drawers' and doors' positions, each item's
pose, and what the grippers hold. It is updated from what the process modules report
(`observe`), as it would be from perception on a real robot, and it answers every
question planning asks (frames, surfaces, containers and what is in them, collisions:
`cramlite.scene.collision`). Planning may look at hypothetical states
(`world_joint_at`, explicit joints and base poses); nothing here ever moves what executes.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cramlite.errors import SetupError
from cramlite.scene.models import ItemModel, Shape, item_model, kitchen_model, pr2_model
from cramlite.scene.transforms import (
    Pose,
    Quat,
    Vec3,
    inverse,
    matrix_pose,
    planar,
    pose_matrix,
    yaw_quat,
)
from cramlite.world.containers import Container, containers_path, load_containers
from cramlite.world.setup import Setup

BasePose = tuple[float, float, float]
#: The link of a world URDF the robot stands on (not a surface for items).
FLOOR_LINK = "floor"
#: A link turned further than this from square to the axes (|sin 2 yaw|, about 0.6
#: degrees) is drawn on 2D maps by its outline rather than its axis-aligned bounds.
TURNED_SIN = 0.02
ARMS = ("right", "left")


def tool_frame(arm: str) -> str:
    return f"{arm[0]}_gripper_tool_frame"


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
class Held:
    """An item in a gripper: the arm, and the item's frame in the tool frame (4 x 4)."""

    arm: str
    relative: np.ndarray


@dataclass(frozen=True)
class SceneItem:
    name: str
    type: str
    model: ItemModel

    @property
    def extents(self) -> tuple[float, float, float]:
        return self.model.extents

    def height(self) -> float:
        return self.model.extents[2]

    def is_round(self) -> bool:
        return self.model.round


@dataclass
class Belief:
    """What the scene believes now (copied and restored around hypothetical looks)."""

    base: BasePose
    joints: dict[str, float]
    world_joints: dict[str, float]
    poses: dict[str, Pose]
    held: dict[str, Held] = field(default_factory=dict)


def loader_message(exc: BaseException) -> str:
    """A C++ loader's exception (coal's and Pinocchio's say where in their source they
    were raised, over several lines) as one line: what went wrong."""
    text = str(exc)
    if "message:" in text:
        text = text.split("message:", 1)[1]
    return "; ".join(line.strip() for line in text.splitlines() if line.strip()) or \
        type(exc).__name__


class PlanningScene:
    """The robot (PR2), a world URDF with its containers, and a setup's items."""

    def __init__(self, setup: Setup):
        self.setup = setup
        self.robot = pr2_model()
        try:
            self.kitchen = kitchen_model(setup.world_urdf)
        except (ValueError, RuntimeError) as exc:
            raise SetupError(f"{setup.world_urdf}: {loader_message(exc)}",
                             source=str(setup.source), field="world") from None
        self.containers: dict[str, Container] = load_containers(setup.world_urdf)
        self._check_containers()
        self.items: dict[str, SceneItem] = {}
        for i, spec in enumerate(setup.items):
            try:
                model = item_model(spec.urdf, spec.type)
            except (ValueError, RuntimeError) as exc:
                raise SetupError(f"{spec.urdf}: {loader_message(exc)}", source=str(setup.source),
                                 field=f"items[{i}].type") from None
            self.items[spec.name] = SceneItem(spec.name, spec.type, model)
        start = setup.robot_start
        self.belief = Belief(
            base=(start.x, start.y, start.yaw),
            joints=dict.fromkeys(self.robot.joints, 0.0),
            world_joints=dict.fromkeys(self.kitchen.joints, 0.0),
            poses={s.name: (s.pose.xyz, yaw_quat(s.pose.yaw)) for s in setup.items})
        self.initial = self.copy_belief()
        #: Data derived from the fixed geometry (maps, the collision checker), kept with
        #: the scene by the layers that need it.
        self.cache: dict[Any, Any] = {}
        self._kitchen_frames: dict[tuple, dict[str, np.ndarray]] = {}
        self._item_matrices: dict[str, tuple[Any, np.ndarray]] = {}  # (by the pose)

    def _check_containers(self) -> None:
        src = str(containers_path(self.setup.world_urdf))
        for container in self.containers.values():
            for link in (container.link, container.handle, container.inside_link):
                if link not in self.kitchen.link_frames:
                    raise SetupError(f"container {container.name!r}: the world has no link "
                                     f"{link!r}", source=src)
            if container.joint not in self.kitchen.joints:
                raise SetupError(f"container {container.name!r}: the world has no movable "
                                 f"joint {container.joint!r}", source=src)
            joint = self.kitchen.joints[container.joint]
            if not joint.lower <= container.open_value <= joint.upper:
                raise SetupError(f"container {container.name!r}: open {container.open_value:g} "
                                 f"is outside its joint's limits; expected a value from "
                                 f"{joint.lower:g} to {joint.upper:g} ({container.joint!r} in "
                                 "the world's URDF)", source=src,
                                 field=f"containers.{container.name}.open")

    # -- the belief ----------------------------------------------------------------------
    @property
    def base(self) -> BasePose:
        return self.belief.base

    @property
    def held(self) -> dict[str, Held]:
        return self.belief.held

    def copy_belief(self) -> Belief:
        b = self.belief
        return Belief(b.base, dict(b.joints), dict(b.world_joints), dict(b.poses),
                      dict(b.held))

    def reset(self, belief: Belief | None = None) -> None:
        """Back to a belief (default: the setup's start)."""
        b = belief or self.initial
        self.belief = Belief(b.base, dict(b.joints), dict(b.world_joints), dict(b.poses),
                             dict(b.held))

    def observe(self, modules) -> None:
        """Update the belief from what the process modules report: base pose, joints,
        drawers and doors, and every item's pose (perception on a real robot)."""
        b = self.belief
        b.base = tuple(float(v) for v in modules.base_pose())
        b.joints.update(modules.joint_positions(list(self.robot.joints)))
        b.world_joints.update(modules.world_joint_positions())
        for name in self.items:
            position, orientation = modules.object_pose(name)
            b.poses[name] = (tuple(map(float, position)), tuple(map(float, orientation)))

    def joint_positions(self, names: Sequence[str] | None = None) -> dict[str, float]:
        joints = self.belief.joints
        return dict(joints) if names is None else {n: joints[n] for n in names}

    def world_joint_positions(self) -> dict[str, float]:
        return dict(self.belief.world_joints)

    def object_pose(self, name: str) -> Pose:
        return self.belief.poses[name]

    def attach(self, arm: str, item: str) -> None:
        """The item is in the gripper now: it moves with the tool frame (its pose in the
        tool frame as the scene sees them both now)."""
        tool = self.link_matrix(tool_frame(arm))
        self.belief.held[item] = Held(arm, inverse(tool) @ pose_matrix(*self.object_pose(item)))

    def detach(self, item: str) -> None:
        self.belief.held.pop(item, None)

    def holding(self, arm: str) -> str | None:
        return next((n for n, h in self.belief.held.items() if h.arm == arm), None)

    # -- the robot ----------------------------------------------------------------------
    def link_matrices(self, links: Sequence[str], joints: dict[str, float] | None = None,
                      base: BasePose | None = None) -> dict[str, np.ndarray]:
        """World frames (4 x 4) of robot links, the robot as believed (or with `joints`
        overriding some of its joints, and at `base`)."""
        values = self.belief.joints if not joints else {**self.belief.joints, **joints}
        frames = self.robot.link_placements(values, list(links))
        world = planar(*(base or self.belief.base))
        return {name: world @ frame for name, frame in frames.items()}

    def link_matrix(self, link: str, joints: dict[str, float] | None = None,
                    base: BasePose | None = None) -> np.ndarray:
        return self.link_matrices([link], joints, base)[link]

    def tool_pose(self, arm: str, joints: dict[str, float] | None = None) -> Pose:
        return matrix_pose(self.link_matrix(tool_frame(arm), joints))

    def held_matrix(self, item: str, joints: dict[str, float] | None = None,
                    base: BasePose | None = None) -> np.ndarray:
        held = self.belief.held[item]
        return self.link_matrix(tool_frame(held.arm), joints, base) @ held.relative

    # -- the kitchen --------------------------------------------------------------------
    def kitchen_frames(self, world_joints: dict[str, float] | None = None,
                       ) -> dict[str, np.ndarray]:
        """Every kitchen link's frame in the world (the drawers and doors as believed, or
        at `world_joints`), cached by the joints' values."""
        values = self.belief.world_joints if world_joints is None else \
            {**self.belief.world_joints, **world_joints}
        key = tuple(round(values[n], 9) for n in self.kitchen.joints)
        frames = self._kitchen_frames.get(key)
        if frames is None:
            if len(self._kitchen_frames) > 256:
                self._kitchen_frames.clear()
            frames = self._kitchen_frames[key] = self.kitchen.link_placements(values)
        return frames

    def link_frame(self, link: str) -> Pose:
        """Pose of a kitchen link's frame in the world (as believed)."""
        return matrix_pose(self.kitchen_frames()[link])

    @contextlib.contextmanager
    def world_joint_at(self, joint: str, value: float, carry: bool = False,
                       ) -> Iterator[None]:
        """Believe a drawer or door at `value` for a look (with `carry`, the items inside
        a drawer ride along), then believe what was believed before."""
        before = self.copy_belief()
        self.set_world_joint(joint, value, carry=carry)
        try:
            yield
        finally:
            self.belief.world_joints = before.world_joints
            self.belief.poses = before.poses

    def set_world_joint(self, joint: str, value: float, carry: bool = True,
                        exclude: Sequence[str] = ()) -> None:
        """Believe a drawer or door at `value`; items inside a drawer (but `exclude` and
        what is held) ride along when `carry`."""
        container = self.container_of_joint(joint)
        riding = []
        if carry and container is not None:
            frame = self.kitchen_frames()[container.link]
            for item in self.riding_along(joint, exclude):
                riding.append((item, inverse(frame) @ pose_matrix(*self.object_pose(item))))
        self.belief.world_joints = {**self.belief.world_joints, joint: float(value)}
        if riding:
            frame = self.kitchen_frames()[container.link]
            poses = dict(self.belief.poses)
            for item, relative in riding:
                poses[item] = matrix_pose(frame @ relative)
            self.belief.poses = poses

    def riding_along(self, joint: str, exclude: Sequence[str] = ()) -> list[str]:
        """The items that move with a drawer's joint: those inside it, but `exclude` and
        what is held (none for a door: what stands in a cupboard stays)."""
        container = self.container_of_joint(joint)
        if container is None or container.inside_link != container.link:
            return []
        return self.items_inside(container, set(exclude) | set(self.belief.held))

    def container_of_joint(self, joint: str) -> Container | None:
        return next((c for c in self.containers.values() if c.joint == joint), None)

    def kitchen_shapes(self) -> list[tuple[Shape, np.ndarray]]:
        """Every collision shape of the kitchen with its world placement, as believed."""
        frames = self.kitchen_frames()
        return [(shape, frames[shape.link] @ shape.in_link) for shape in self.kitchen.shapes]

    def surface(self, name: str) -> Surface:
        """A kitchen link's top and extent (the bounds of its shapes, as believed)."""
        if name not in self.kitchen.shapes_by_link:
            raise KeyError(name)
        lo, hi = self.link_bounds(name)
        return Surface(name, lo[0], hi[0], lo[1], hi[1], hi[2])

    def link_bounds(self, link: str, world_joints: dict[str, float] | None = None,
                    ) -> tuple[Vec3, Vec3]:
        """Axis-aligned bounds of a kitchen link's shapes in the world."""
        frame = self.kitchen_frames(world_joints)[link]
        corners = [shape_corners(shape, frame @ shape.in_link)
                   for shape in self.kitchen.shapes_by_link[link]]
        pts = np.vstack(corners)
        return tuple(pts.min(axis=0).tolist()), tuple(pts.max(axis=0).tolist())

    def surfaces(self) -> list[str]:
        """The kitchen links items may stand on (every link with a shape but the floor)."""
        return [n for n in self.kitchen.shapes_by_link if n != FLOOR_LINK]

    def surface_under(self, x: float, y: float, z: float, tolerance: float) -> Surface | None:
        """The surface (not the floor) whose top is at z (within `tolerance`) under x, y."""
        # (the surfaces as they stand with the drawers and doors where they are now, kept)
        key = ("surfaces", tuple(sorted(self.belief.world_joints.items())))
        surfaces = self.cache.get(key)
        if surfaces is None:
            surfaces = self.cache[key] = [self.surface(name) for name in self.surfaces()]
        for surf in surfaces:
            if surf.contains_xy(x, y) and abs(z - surf.top_z) <= tolerance:
                return surf
        return None

    def support_under(self, point: Sequence[float], tolerance: float) -> str | None:
        """What an item whose bottom centre is at `point` would stand on: a surface whose
        top is there (within `tolerance`), or a container whose inside bottom is there
        (with the container where it is now, or closed: how places in drawers are given);
        None if nothing (in the air, off an edge, below the floor)."""
        x, y, z = (float(v) for v in point)
        surface = self.surface_under(x, y, z, tolerance)
        if surface is not None:
            return surface.name
        for container in self.containers.values():
            for joints in (None, {container.joint: 0.0}):
                local = self._inside_local(container, (x, y, z), joints)
                if self._within(container, local) and \
                        abs(local[2] - container.inside_min[2]) <= tolerance:
                    return container.name
        return None

    def moving_links(self) -> set[str]:
        """Kitchen links a drawer's or door's joint moves."""
        return {link for link in self.kitchen.shapes_by_link
                if self.kitchen.parent_joint(link) is not None}

    def links_moved_by(self, joint: str) -> set[str]:
        return {link for link in self.kitchen.link_frames
                if joint in self.kitchen.joints_above(link)}

    def environment_footprints(self) -> list[tuple[str, Vec3, Vec3, list[np.ndarray] | None]]:
        """(name, lower and upper corner, outlines) of each kitchen link with a shape, as
        believed: what 2D maps are drawn from; `outlines` are the xy corners of each box of
        a link turned about the vertical (a door swung open), whose axis-aligned bounds
        would cover far more than it does (None otherwise)."""
        frames = self.kitchen_frames()
        out = []
        for name, shapes in self.kitchen.shapes_by_link.items():
            lo, hi = self.link_bounds(name)
            outlines = None
            frame = frames[name]
            yaw = math.atan2(frame[1, 0], frame[0, 0])
            if self.kitchen.parent_joint(name) is not None and \
                    abs(math.sin(2 * yaw)) >= TURNED_SIN and all(s.kind == "box" for s in shapes):
                outlines = [shape_corners(s, frame @ s.in_link)[:, :2] for s in shapes]
            out.append((name, lo, hi, outlines))
        return out

    # -- containers ---------------------------------------------------------------------
    def _inside_local(self, container: Container, position: Sequence[float],
                      world_joints: dict[str, float] | None = None) -> np.ndarray:
        frame = self.kitchen_frames(world_joints)[container.inside_link]
        return (inverse(frame) @ np.array([*position, 1.0]))[:3]

    @staticmethod
    def _within(container: Container, local: np.ndarray) -> bool:
        (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
        return bool(x0 <= local[0] <= x1 and y0 <= local[1] <= y1 and
                    z0 - 0.02 <= local[2] <= z1)

    def items_inside(self, container: Container, exclude: set[str] | None = None) -> list[str]:
        """Items standing inside a container now (by where they are believed to be)."""
        return [name for name, (position, _) in self.belief.poses.items()
                if not (exclude and name in exclude)
                and self._within(container, self._inside_local(container, position))]

    def container_of(self, item: str) -> Container | None:
        """The container an item is inside now, if any (not if it is held)."""
        if item in self.belief.held:
            return None
        return next((c for c in self.containers.values() if item in self.items_inside(c)),
                    None)

    def container_at(self, point: Sequence[float]) -> tuple[Container, Vec3] | tuple[None, None]:
        """The container whose inside holds a point given as it is with the container
        closed, and the point in the inside's frame; (None, None) if none."""
        for container in self.containers.values():
            local = self._inside_local(container, point, {container.joint: 0.0})
            if self._within(container, local):
                return container, tuple(float(v) for v in local)
        return None, None

    def inside_yaw(self, container: Container) -> float:
        """The yaw of a container's inside frame in the world (as it is closed: a drawer
        slides, the inside of a cupboard stays)."""
        frame = self.kitchen_frames({container.joint: 0.0})[container.inside_link]
        return math.atan2(frame[1, 0], frame[0, 0])

    def inside_point(self, container: Container, local: Sequence[float]) -> Vec3:
        """A point given in a container's inside frame, in the world as believed."""
        frame = self.kitchen_frames()[container.inside_link]
        return tuple(float(v) for v in (frame @ np.array([*local, 1.0]))[:3])

    def is_open(self, container: Container) -> bool:
        return self.belief.world_joints[container.joint] >= container.open_value - 1e-3

    # -- items ----------------------------------------------------------------------------
    def item_matrix(self, name: str) -> np.ndarray:
        """An item's frame in the world (a held one where its gripper is)."""
        if name in self.belief.held:
            return self.held_matrix(name)
        position, orientation = self.belief.poses[name]
        key = np.array((*position, *orientation), dtype=float).tobytes()  # (-0.0 is not 0.0)
        found = self._item_matrices.get(name)
        if found is None or found[0] != key:
            found = self._item_matrices[name] = (key, pose_matrix(position, orientation))
        return found[1].copy()

    def item_shapes(self, name: str, frame: np.ndarray | None = None,
                    ) -> list[tuple[Shape, np.ndarray]]:
        frame = self.item_matrix(name) if frame is None else frame
        return [(shape, frame @ shape.in_link) for shape in self.items[name].model.shapes]


def shape_corners(shape: Shape, placement: np.ndarray) -> np.ndarray:
    """The corners (8 x 3, world) of a shape's local bounds placed at `placement` (a
    mesh's vertices instead: its bounds turned would overstate it)."""
    if shape.vertices is not None:
        local = shape.vertices
    else:
        local = _UNIT_CORNERS * shape.half + shape.centre
    return local @ placement[:3, :3].T + placement[:3, 3]


def shapes_bounds(shapes: Sequence[Shape]) -> tuple[np.ndarray, np.ndarray]:
    """The bounds (lo, hi) of shapes in the frame they are given in (an item's: its
    shapes' `in_link`)."""
    corners = np.vstack([shape_corners(shape, shape.in_link) for shape in shapes])
    return corners.min(axis=0), corners.max(axis=0)


def gap_to_bounds(point: np.ndarray, frame: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray) -> float:
    """The distance from a world point to bounds lo..hi given in `frame` (0 inside them):
    how far a gripper's tool frame is from what it would hold."""
    local = frame[:3, :3].T @ (np.asarray(point) - frame[:3, 3])
    return float(np.linalg.norm(np.maximum(0.0, np.maximum(lo - local, local - hi))))


#: A box's corners at unit half extents.
_UNIT_CORNERS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                          for sz in (-1, 1)], dtype=float)


__all__ = ["ARMS", "BasePose", "Belief", "FLOOR_LINK", "Held", "PlanningScene", "Quat",
           "SceneItem", "Surface", "Vec3", "shape_corners", "tool_frame"]
