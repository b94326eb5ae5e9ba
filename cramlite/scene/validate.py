"""Refusing a setup a trial could not start from, on the planning scene (any backend).

Every item stands on its surface, its centre of mass inside the top's edges by a margin
(or fits inside its container), and starts inside nothing else; every target rests on the
top of a surface likewise (or fits inside the container it is in), free of the furniture
and of the other targets; the robot stands on the kitchen floor, inside no furniture and no
item, with its arms parked and as a trial begins (stretched out). Each refusal is a
`SetupError` naming the file, the field and what was expected.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from cramlite.errors import SetupError
from cramlite.scene.collision import SceneCollisions
from cramlite.scene.models import Shape
from cramlite.scene.scene import FLOOR_LINK, PlanningScene, Surface, shape_corners
from cramlite.scene.transforms import pose_matrix, yaw_quat
from cramlite.world.containers import Container, containers_path, turned_halves
from cramlite.world.pr2 import PARK_JOINTS
from cramlite.world.setup import ItemSpec, Setup

#: Penetration deeper than this between an item and another body is "inside" it.
PENETRATION_TOLERANCE_M = 0.005
#: An item must start within this height of its surface's top.
SURFACE_HEIGHT_TOLERANCE_M = 0.01
#: An item's centre of mass stands at least this far inside the edges of the top it
#: stands on (at its start and at its target): over an edge it tips off, right at one a
#: nudge tips it (a bowl with its middle at the counter's front edge fell to the floor on
#: PyBullet). Its footprint may overhang the edge (a spoon's handle).
SUPPORT_MARGIN_M = 0.02

Placed = list[tuple[Shape, np.ndarray]]


def check_setup(scene: PlanningScene) -> None:
    """Raise SetupError if the setup's scene is impossible (see the module's doc)."""
    setup = scene.setup
    src = str(setup.source)

    def fail(fld: str, message: str) -> SetupError:
        return SetupError(message, source=src, field=fld)

    from cramlite.designators.locations import TARGET_RINGS_M  # (where it may be put)

    _check_graspable(scene, fail)
    collisions = SceneCollisions(scene)
    surfaces = scene.surfaces()
    tops = [scene.surface(name) for name in scene.kitchen.shapes_by_link]  # (the floor too)
    #: A target's centre of mass is inside its top's edges by this much more: the robot may
    #: put the item that far from its target.
    put_off = max(TARGET_RINGS_M)
    for i, spec in enumerate(setup.items):
        where = f"items[{i}]"
        target = spec.target  # (wherever the item starts: a target needs something under it)
        support = scene.support_under(target.xyz, SURFACE_HEIGHT_TOLERANCE_M)
        if support is None:
            raise fail(f"{where}.target",
                       f"target of {spec.name!r} at {_xyz(target.xyz)} rests on no "
                       f"surface (in the air, off the edge or below the floor); expected "
                       f"z = the top of a surface under it (one of {', '.join(surfaces)}) "
                       "or the bottom of a drawer or cupboard it is in")
        inside, _ = scene.container_at(target.xyz)
        if inside is not None:  # (a target in a drawer or the cupboard: the item fits)
            _check_fits(scene, spec, target, inside, src, f"{where}.target")
        elif support in scene.kitchen.shapes_by_link:  # (on a surface: it stands there)
            surf = scene.surface(support)
            margin = SUPPORT_MARGIN_M + put_off
            if not _supported(scene, spec.name, target, surf, tops, margin):
                raise fail(f"{where}.target",
                           f"target of {spec.name!r} at {_xyz(target.xyz)} is at the edge of "
                           f"{surf.name!r} ({_com_inside(scene, spec.name, target, surf)}); "
                           f"expected {_allowed(scene, spec.name, target, surf, margin)} (its "
                           f"centre of mass {SUPPORT_MARGIN_M:.2f} m inside the edges, so "
                           f"that it cannot tip, and {put_off:.2f} m more: the robot may "
                           f"put it that far from its target)")
        if spec.container is not None:
            _check_in_container(scene, spec, src, where)
            continue
        if spec.surface not in scene.kitchen.shapes_by_link:
            raise fail(f"{where}.surface", f"unknown surface {spec.surface!r}; expected "
                                           f"one of {', '.join(surfaces)}")
        surf = scene.surface(spec.surface)
        on_top = abs(spec.pose.z - surf.top_z) <= SURFACE_HEIGHT_TOLERANCE_M
        if not (on_top and
                _supported(scene, spec.name, spec.pose, surf, tops, SUPPORT_MARGIN_M)):
            why = f" ({_com_inside(scene, spec.name, spec.pose, surf)})" if on_top else ""
            raise fail(f"{where}.pose",
                       f"item {spec.name!r} at {_xyz(spec.pose.xyz)} is not on "
                       f"{spec.surface!r}{why}; expected "
                       f"{_allowed(scene, spec.name, spec.pose, surf, SUPPORT_MARGIN_M)}, "
                       f"z = {surf.top_z:.2f} (its centre of mass {SUPPORT_MARGIN_M:.2f} m "
                       "inside the edges, so that it cannot tip)")
    _check_robot_start(scene, collisions, fail)
    kitchen = [(s, p) for s, p in scene.kitchen_shapes() if s.link != FLOOR_LINK]
    robot = [placed for _, shapes in _robot_poses(scene) for placed in shapes]
    starts = {spec.name: _item_at(scene, spec.name, spec.pose) for spec in setup.items}
    for i, spec in enumerate(setup.items):
        mine = starts[spec.name]
        others = [("the environment", kitchen), ("the robot", robot)] + [
            (repr(name), placed) for name, placed in starts.items() if name != spec.name]
        for label, placed in others:
            depth = _deepest(collisions, mine, placed)
            if depth > PENETRATION_TOLERANCE_M:
                raise fail(f"items[{i}].pose",
                           f"item {spec.name!r} starts inside {label} (overlap "
                           f"{depth * 100:.1f} cm); expected a free spot")
    _check_targets(scene, collisions, kitchen, fail)


#: How far the arm reaches from the base's middle in practice (the location designators
#: try base poses up to 0.80 m away; beyond 0.75 m few have IK: a spoon on the counter with
#: the floor 0.79 m away failed, 0.73 m away it was fetched).
REACH_MAX_M = 0.75


def reach_problems(scene: PlanningScene) -> list[str]:
    """What the robot will not reach, one line each: every item on a surface and every
    target needs floor around it where the base can stand within an arm's reach, as the
    location designators will look for it (the PR2's base square free of the fixed world,
    from their nearest standoff out, facing it). A setup may hold such an item on purpose
    (`unreachable` shows how a plan fails), so this is a warning of `show`, not an
    error."""
    from cramlite.designators.context import occupancy_map
    from cramlite.motion.footprint import FootprintChecker

    checker = FootprintChecker(occupancy_map(scene))
    out = []
    for i, spec in enumerate(scene.setup.items):
        spots = [("target", spec.target.x, spec.target.y)]
        if spec.container is None:
            spots.insert(0, ("pose", spec.pose.x, spec.pose.y))
        for field, x, y in spots:
            nearest = _nearest_standing(checker, x, y)
            if nearest is not None and nearest <= REACH_MAX_M + 1e-9:
                continue
            what = f"item {spec.name!r}" if field == "pose" else f"the target of {spec.name!r}"
            line = f"items[{i}].{field}: {what} at ({x:.2f}, {y:.2f}) is out of the robot's reach: "
            if nearest is None:
                out.append(line + "no floor within 2.5 m where the base can stand")
            else:
                out.append(line + f"the nearest floor the base can stand on is {nearest:.2f} m "
                           f"from it, an arm reaches about {REACH_MAX_M:.2f} m (put it "
                           f"{nearest - REACH_MAX_M + 0.005:.2f} m nearer the open floor)")
    return out


def _nearest_standing(checker, x: float, y: float) -> float | None:
    """The distance from (x, y) to the nearest base pose facing it whose footprint is
    free (rings 2.5 cm apart from the location designators' nearest standoff, 72
    directions), or None within 2.5 m."""
    from cramlite.designators.locations import STANDOFFS_M

    for radius in np.arange(STANDOFFS_M[0], 2.5 + 1e-9, 0.025):
        for angle in np.linspace(-np.pi, np.pi, 72, endpoint=False):
            bx, by = x + radius * np.cos(angle), y + radius * np.sin(angle)
            if checker.is_free(float(bx), float(by), float(angle + np.pi)):
                return float(radius)
    return None


def _centre_of_mass_xy(scene: PlanningScene, name: str, pose) -> np.ndarray:
    """Where an item's centre of mass is, seen from above, with the item at `pose`."""
    cx, cy, _ = scene.items[name].model.centre_of_mass
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return np.array([pose.x + c * cx - s * cy, pose.y + s * cx + c * cy])


def _supported(scene: PlanningScene, name: str, pose, on: Surface, tops: list[Surface],
               margin: float) -> bool:
    """Is the item's centre of mass, with the item at `pose`, over the top `on` and at
    least `margin` inside the edges of the tops at its bottom's height (a square of that
    half size about it, its corners and middles, on them: on two tops that meet, across
    their seam)?"""
    com = _centre_of_mass_xy(scene, name, pose)
    level = [t for t in tops if abs(pose.z - t.top_z) <= SURFACE_HEIGHT_TOLERANCE_M]
    return on.contains_xy(*com) and all(
        any(t.contains_xy(float(x), float(y)) for t in level)
        for x, y in com + (margin - 1e-9) * _SQUARE)  # (x = 1.27 is on)


#: A square's corners, the middles of its sides and its centre, at half size 1.
_SQUARE = np.array([(sx, sy) for sx in (-1, 0, 1) for sy in (-1, 0, 1)], dtype=float)


def _com_inside(scene: PlanningScene, name: str, pose, surf: Surface) -> str:
    """How far inside a top's edges the item's centre of mass is (for messages)."""
    x, y = _centre_of_mass_xy(scene, name, pose)
    inside = min(x - surf.x_min, surf.x_max - x, y - surf.y_min, surf.y_max - y)
    if inside < 0:
        return f"its centre of mass {-inside:.3f} m beyond its edge"
    return f"its centre of mass {inside:.3f} m inside its edge"


def _allowed(scene: PlanningScene, name: str, pose, surf: Surface, margin: float) -> str:
    """The x and y an item at `pose` (its yaw) may be given on a top (for messages)."""
    dx, dy = _centre_of_mass_xy(scene, name, pose) - (pose.x, pose.y)
    x0, x1 = surf.x_min + margin - dx, surf.x_max - margin - dx
    y0, y1 = surf.y_min + margin - dy, surf.y_max - margin - dy
    if x0 > x1 or y0 > y1:
        return (f"a top larger than {surf.name!r} ({surf.x_max - surf.x_min:.2f} x "
                f"{surf.y_max - surf.y_min:.2f} m)")
    return f"x in [{x0:.2f}, {x1:.2f}], y in [{y0:.2f}, {y1:.2f}]"


def _xyz(values: Iterable[float]) -> str:
    """A position as messages give it: [-0.8, 2.28, 0.86], not 2.2800000000000002."""
    return repr([round(float(v), 6) for v in values])


def _item_at(scene: PlanningScene, name: str, pose) -> Placed:
    frame = pose_matrix(pose.xyz, yaw_quat(pose.yaw))
    return scene.item_shapes(name, frame)


def _deepest(collisions: SceneCollisions, a: Placed, b: Placed) -> float:
    """The deepest penetration between two sets of placed shapes (bounds first)."""
    return _deepest_pair(collisions, a, b)[0]


def _deepest_pair(collisions: SceneCollisions, a: Placed, b: Placed,
                  ) -> tuple[float, Shape | None]:
    """The deepest penetration between two sets of placed shapes (bounds first), and the
    shape of `a` it is of (None if none is inside another)."""
    deepest, which = 0.0, None
    if not a or not b:
        return deepest, which
    # (each shape's corners, or a mesh's vertices, placed: their bounds)
    corners_a = [shape_corners(sa, pa) for sa, pa in a]
    corners_b = [shape_corners(sb, pb) for sb, pb in b]
    lo_a = np.array([c.min(axis=0) for c in corners_a])
    hi_a = np.array([c.max(axis=0) for c in corners_a])
    lo_b = np.array([c.min(axis=0) for c in corners_b])
    hi_b = np.array([c.max(axis=0) for c in corners_b])
    apart = np.any((hi_a[:, None] < lo_b[None]) | (hi_b[None] < lo_a[:, None]), axis=2)
    for i, j in np.argwhere(~apart).tolist():
        (sa, pa), (sb, pb) = a[i], b[j]
        depth = collisions.depth(sa, pa, sb, pb)
        if depth > deepest:
            deepest, which = depth, sa
    return deepest, which


def _robot_poses(scene: PlanningScene) -> list[tuple[str, Placed]]:
    """The robot's shapes (every link's: base, torso, head, arms, grippers) at its start,
    as a plan has them there, each with what they are (for messages): with the arms
    parked (the torso down), and as a trial begins, every joint at zero (the arms
    stretched out forward, the grippers closed), from where a plan parks them first."""
    start = scene.setup.robot_start
    base = (start.x, start.y, start.yaw)
    initial = dict(scene.initial.joints)
    parked = {**initial, **{k: v for arm in PARK_JOINTS.values() for k, v in arm.items()}}
    out = []
    for how, joints in (("its arms parked", parked),
                        ("its arms as a trial begins, stretched out before it parks them",
                         initial)):
        frames = scene.link_matrices(list(scene.robot.shapes_by_link), joints, base)
        out.append((how, [(shape, frames[link] @ shape.in_link)
                          for link, shapes in scene.robot.shapes_by_link.items()
                          for shape in shapes]))
    return out


def _check_graspable(scene: PlanningScene, fail) -> None:
    """Every item has a grasp the gripper can make (its item file's kinds, its widths)."""
    from cramlite.designators.grasps import item_grasps  # (what a hand can do with it)

    for i, spec in enumerate(scene.setup.items):
        try:
            item_grasps(scene.items[spec.name].model)
        except SetupError as exc:
            raise fail(f"items[{i}].type", f"item {spec.name!r}: {exc.detail} (from "
                                           f"{exc.source})") from None


def _check_in_container(scene: PlanningScene, spec: ItemSpec, src: str, where: str) -> None:
    """An item `in:` a container names one of the world's and fits inside it."""
    container = scene.containers.get(spec.container)
    if container is None:
        path = containers_path(scene.setup.world_urdf)
        if scene.containers:
            known = f"one of {', '.join(scene.containers)} (from {path})"
        elif path.exists():
            known = f"none ({path} lists none)"
        else:
            known = f"none (this world has none: there is no {path} beside its URDF)"
        raise SetupError(f"unknown container {spec.container!r}; expected {known}",
                         source=src, field=f"{where}.in")
    _check_fits(scene, spec, spec.pose, container, src, f"{where}.pose")


def _check_fits(scene: PlanningScene, spec: ItemSpec, pose, container: Container, src: str,
                fld: str) -> None:
    """The item at `pose` (its start `in:` a container, or its target inside one, given as
    it is with the container closed) stands on the inside's bottom, its bounds turned to
    its yaw within the inside's walls, and is no taller than the inside."""
    local = scene._inside_local(container, pose.xyz, {container.joint: 0.0})
    ex, ey, ez = scene.items[spec.name].extents
    half_x, half_y = turned_halves((ex, ey), pose.yaw - scene.inside_yaw(container))
    if not container.fits(tuple(local), half_x, half_y, ez):
        (x0, y0, z0), (x1, y1, z1) = container.inside_min, container.inside_max
        frame = scene.kitchen_frames({container.joint: 0.0})[container.inside_link]
        bottom = float((frame @ np.array([0.0, 0.0, z0, 1.0]))[2])
        what = f"item {spec.name!r}" if fld.endswith(".pose") else f"target of {spec.name!r}"
        raise SetupError(
            f"{what} ({ex:.2f} x {ey:.2f} x {ez:.2f} m) at {_xyz(pose.xyz)} does not fit in "
            f"{container.name!r}; expected it standing on its bottom (z = {bottom:.2f}), "
            f"inside {x1 - x0:.2f} x {y1 - y0:.2f} m and at most {z1 - z0:.2f} m tall",
            source=src, field=fld)


def _check_robot_start(scene: PlanningScene, collisions: SceneCollisions, fail) -> None:
    """The robot at its start with its arms parked is on the floor, and no link of it,
    arms parked or as a trial begins (see `_robot_poses`), is inside the kitchen or an
    item (coal's depth of each shape in each: `PENETRATION_TOLERANCE_M` allowed)."""
    start = scene.setup.robot_start
    poses = _robot_poses(scene)
    # (on the floor: the parked robot; arms stretched out over its edge meet a wall, if any)
    points = np.vstack([shape_corners(s, p) for s, p in poses[0][1]])
    lo, hi = points.min(axis=0), points.max(axis=0)
    if FLOOR_LINK in scene.kitchen.shapes_by_link:
        floor = scene.surface(FLOOR_LINK)
        if not (floor.contains_xy(lo[0], lo[1]) and floor.contains_xy(hi[0], hi[1])):
            raise fail("robot.start",
                       f"the robot at ({start.x:g}, {start.y:g}) is not on the floor of the "
                       f"kitchen; expected x in [{floor.x_min:.2f}, {floor.x_max:.2f}], y in "
                       f"[{floor.y_min:.2f}, {floor.y_max:.2f}] with room for the robot")
    for how, robot in poses:
        found = {link: _deepest_pair(collisions, robot, _link_shapes(scene, [link]))
                 for link in scene.kitchen.shapes_by_link if link != FLOOR_LINK}
        link = max(found, key=lambda k: found[k][0], default=None)
        if link is not None and found[link][0] > PENETRATION_TOLERANCE_M:
            depth, shape = found[link]
            raise fail("robot.start",
                       f"the robot at ({start.x:g}, {start.y:g}) starts inside {link!r} "
                       f"(overlap {depth * 100:.1f} cm: its {shape.link}, with {how}); "
                       "expected a free spot on the floor")
        for i, spec in enumerate(scene.setup.items):
            depth, shape = _deepest_pair(collisions, robot,
                                         _item_at(scene, spec.name, spec.pose))
            if depth > PENETRATION_TOLERANCE_M:
                raise fail("robot.start",
                           f"the robot at ({start.x:g}, {start.y:g}) starts inside item "
                           f"{spec.name!r} (items[{i}]; overlap {depth * 100:.1f} cm: its "
                           f"{shape.link}, with {how}); expected a free spot")


def _link_shapes(scene: PlanningScene, links: Iterable[str]) -> Placed:
    frames = scene.kitchen_frames()
    return [(s, frames[s.link] @ s.in_link) for link in links
            for s in scene.kitchen.shapes_by_link[link]]


def _check_targets(scene: PlanningScene, collisions: SceneCollisions, kitchen: Placed,
                   fail) -> None:
    """Every item at its target is free of the furniture and of the other targets."""
    setup: Setup = scene.setup
    at_targets = {spec.name: _item_at(scene, spec.name, spec.target) for spec in setup.items}
    for i, spec in enumerate(setup.items):
        mine = at_targets[spec.name]
        depth = _deepest(collisions, mine, kitchen)
        if depth > PENETRATION_TOLERANCE_M:
            raise fail(f"items[{i}].target",
                       f"target of {spec.name!r} at {_xyz(spec.target.xyz)} is inside the "
                       f"furniture (overlap {depth * 100:.1f} cm); expected a free spot on a "
                       "surface")
        for j, other in enumerate(setup.items[:i]):
            depth = _deepest(collisions, mine, at_targets[other.name])
            if depth > PENETRATION_TOLERANCE_M:
                raise fail(f"items[{i}].target",
                           f"target of {spec.name!r} overlaps the target of {other.name!r} "
                           f"(items[{j}]) by {depth * 100:.1f} cm; expected a spot of its own")
