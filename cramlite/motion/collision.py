"""Is a robot configuration collision-free? Checked in the robot's PyBullet world.

A `CollisionScene` fixes what one motion query moves (a set of joints, the objects held
in the grippers) and what it may touch (the object being manipulated). A state is free
when no moving robot link is inside the kitchen or inside an item other than the
manipulated one, and no held object is inside the kitchen or another item, each
allowing `tolerance_m` of penetration (PyBullet uses convex hulls of the PR2's meshes).

Only links that move can newly collide, so only they are checked (PITFALLS: the arm's
links are ~4x cheaper than the whole robot). A broadphase of spheres (one per moving link
and held object) against the obstacles' boxes (axis-aligned, or turned where a door has
swung open), a few numpy calls for one state or for every state of a motion, leaves
PyBullet's exact query (`getClosestPoints`, which reports penetrations even with the
robot's collision filter off) to the few link-obstacle pairs that can touch.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from cramlite.motion.link_frames import LinkFrames
from cramlite.world.bodies import Quat, Vec3
from cramlite.world.bullet import p
from cramlite.world.quiet import c_stdout_silenced

#: Penetration allowed for the convex-hull approximation of the robot's meshes: 1 cm, less
#: 2 mm in the states a motion is checked at (a link moving up to 2 cm between two of them
#: may go a little deeper on the way, and the trace's check allows 1 cm there too).
PENETRATION_TOLERANCE_M = 0.008


@dataclass(frozen=True)
class HeldObject:
    """An object that moves with a robot link (a gripper's tool frame)."""

    name: str
    link: str  #: the robot link it is attached to
    relative: tuple[Vec3, Quat]  #: its pose in that link's frame


@dataclass(frozen=True)
class Contact:
    """A penetration found by `CollisionScene.contacts` (for messages and tests)."""

    what: str  #: robot link or held object
    other: str  #: environment link or item
    depth_m: float

    def describe(self) -> str:
        return f"{self.what} {self.depth_m * 100:.1f} cm inside {self.other}"


class CollisionChecker:
    """Builds collision scenes in one world (robot, environment, items).

    Every robot link with a collision shape gets a bounding sphere in its own frame
    (from its box at the zero configuration), the broadphase of every scene."""

    def __init__(self, world, tolerance_m: float = PENETRATION_TOLERANCE_M):
        self.world = world
        self.client = world.client
        self.robot = world.robot
        self.tolerance_m = tolerance_m
        body, client = self.robot.body, self.client
        count = p.getNumJoints(body, physicsClientId=client)
        self._parent = {j: p.getJointInfo(body, j, physicsClientId=client)[16]
                        for j in range(count)}
        self.link_names = {j: p.getJointInfo(body, j, physicsClientId=client)[12].decode()
                           for j in range(count)}
        self._has_shape = {j for j in range(count)
                           if p.getCollisionShapeData(body, j, physicsClientId=client)}
        self._moving_links_cache: dict[frozenset[str], list[int]] = {}
        self.spheres, self.mass_spheres = self._link_spheres()
        self._link_frames: LinkFrames | None = None
        self._mass_centres: dict[int, np.ndarray] = {}
        self.link_frames()  # (Pinocchio's model of the robot, calibrated: with the world)

    def link_frames(self) -> LinkFrames:
        """The robot's link frames by Pinocchio (for the broadphase of whole motions)."""
        if self._link_frames is None:
            self._link_frames = LinkFrames(self.robot, self.client)
        return self._link_frames

    def _link_spheres(self) -> tuple[dict[int, tuple[np.ndarray, float]], dict[int, float]]:
        """Link -> (centre in the link frame, radius) of a sphere that holds its shape; and
        link -> radius of a sphere about the link's centre of mass that holds it (PyBullet
        reports that centre's position in the world with the link's state: a state's
        broadphase needs no rotation)."""
        robot, client = self.robot, self.client
        out, about_mass = {}, {}
        with self.preserved():
            robot.set_base_pose(0.0, 0.0, 0.0)
            robot.set_joint_positions(dict.fromkeys(robot.joint_index, 0.0))
            for link in sorted(self._has_shape):
                lo, hi = p.getAABB(robot.body, link, physicsClientId=client)
                state = p.getLinkState(robot.body, link, computeForwardKinematics=True,
                                       physicsClientId=client)
                rotation = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
                corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                    for z in (lo[2], hi[2])])
                local = (corners - np.asarray(state[4])) @ rotation
                centre = local.mean(axis=0)
                out[link] = (centre, float(np.linalg.norm(local - centre, axis=1).max()))
                mass = np.asarray(state[2])  # the centre of mass in the link frame
                about_mass[link] = float(np.linalg.norm(local - mass, axis=1).max())
        return out, about_mass

    def mass_centre(self, link: int) -> np.ndarray:
        """A link's centre of mass in its own frame."""
        if link not in self._mass_centres:
            self._mass_centres[link] = np.asarray(p.getLinkState(
                self.robot.body, link, physicsClientId=self.client)[2])
        return self._mass_centres[link]

    def upper_body_parts(self) -> dict[str, tuple[list[str], list[int]]]:
        """The robot's links above its base with a collision mesh, in three parts (each
        arm, and the rest: torso, head), with the joints that place each part."""
        if not hasattr(self, "_upper_parts"):
            robot, client = self.robot, self.client
            torso = robot.joint_index["torso_lift_joint"]
            arms = {arm: set(self.moving_links([f"{arm[0]}_shoulder_pan_joint"]))
                    for arm in ("right", "left")}
            parts: dict[str, tuple[list[str], list[int]]] = {
                "right": (["torso_lift_joint"] + [n for n in robot.joint_index
                                                  if n.startswith("r_")], []),
                "left": (["torso_lift_joint"] + [n for n in robot.joint_index
                                                 if n.startswith("l_")], []),
                "body": (["torso_lift_joint"], [])}
            self._upper_vertices = {}
            for link in self.moving_links(["torso_lift_joint"]):
                if link == torso:
                    continue
                with c_stdout_silenced():  # PyBullet prints "?" for links without a mesh
                    vertices = p.getMeshData(robot.body, link, physicsClientId=client)[1]
                if not vertices:
                    continue
                self._upper_vertices[link] = np.array(vertices)
                part = next((a for a, links in arms.items() if link in links), "body")
                parts[part][1].append(link)
            self._upper_parts = parts
        return self._upper_parts

    def upper_body_points(self, links: Sequence[int] | None = None) -> list[np.ndarray]:
        """The collision-mesh vertices (world) of robot links above its base (default: all
        of them: arms, torso, head), as the robot stands now."""
        robot, client = self.robot, self.client
        parts = self.upper_body_parts()
        links = list(links) if links is not None else [
            link for _, part in parts.values() for link in part]
        if not links:
            return []
        states = p.getLinkStates(robot.body, links, computeForwardKinematics=True,
                                 physicsClientId=client)
        out = []
        for link, state in zip(links, states, strict=True):
            rotation = np.array(p.getMatrixFromQuaternion(state[1])).reshape(3, 3)
            out.append(self._upper_vertices[link] @ rotation.T + np.asarray(state[0]))
        return out

    # -- what moves ------------------------------------------------------------------------
    def moving_links(self, joints: Sequence[str]) -> list[int]:
        """Links with collision shapes that move when any of `joints` moves."""
        key = frozenset(joints)
        if key not in self._moving_links_cache:
            roots = {self.robot.joint_index[n] for n in joints}
            out = []
            for link in self._parent:
                j = link
                while j >= 0 and j not in roots:
                    j = self._parent[j]
                if j >= 0 and link in self._has_shape:
                    out.append(link)
            self._moving_links_cache[key] = out
        return self._moving_links_cache[key]

    def scene(self, joints: Sequence[str], held: Sequence[HeldObject] = (),
              ignore: Sequence[str] = ()) -> CollisionScene:
        """A scene for motions of `joints` carrying `held`, allowed to touch `ignore` (items
        or environment links, e.g. a handle in the gripper)."""
        return CollisionScene(self, list(joints), list(held), set(ignore))

    # -- robot state, saved and restored ---------------------------------------------------
    @contextlib.contextmanager
    def preserved(self, objects: Sequence[str] = ()) -> Iterator[None]:
        """Restore the robot's base and joints (and these objects' poses) afterwards."""
        robot = self.robot
        base = robot.base_pose()
        joints = robot.joint_positions()
        poses = {n: self.world.objects[n].pose() for n in objects}
        try:
            yield
        finally:
            robot.set_base_pose(*base)
            robot.set_joint_positions(joints)
            for name, (pos, orn) in poses.items():
                self.world.objects[name].set_pose(pos, orn)


def rotate(quaternions: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Rotate vectors (N x 3) by quaternions (N x 4, x y z w), row by row
    (v + 2w (u x v) + 2 u x (u x v), written out: np.cross costs ten times more)."""
    ux, uy, uz, w = quaternions.T
    vx, vy, vz = vectors.T
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    dx, dy, dz = uy * cz - uz * cy, uz * cx - ux * cz, ux * cy - uy * cx
    return np.column_stack([vx + 2 * (w * cx + dx), vy + 2 * (w * cy + dy),
                            vz + 2 * (w * cz + dz)])


class CollisionScene:
    """One motion query's collision problem; `is_free(q)` checks a joint vector.

    Parts are spheres attached to robot links: one per moving link with a shape, one per
    held object (attached to its gripper's tool frame). Obstacles are boxes: the
    environment's links and the items that are neither held nor ignored."""

    def __init__(self, checker: CollisionChecker, joints: list[str], held: list[HeldObject],
                 ignore: set[str]):
        world, robot = checker.world, checker.robot
        self.checker = checker
        self.client = checker.client
        self.body = robot.body
        self.joints = joints
        self.joint_indices = [robot.joint_index[n] for n in joints]
        self.tolerance_m = checker.tolerance_m
        links = checker.moving_links(joints)
        # a body's pose in PyBullet is its inertial frame's: compose it in once
        self.held = [(world.objects[h.name].body, robot.link_index[h.link], h,
                      p.multiplyTransforms(*h.relative, *world.objects[h.name].inertial_frame))
                     for h in held]
        self.query_links = list(dict.fromkeys([*links, *(link for _, link, _, _ in self.held)]))
        row = {link: i for i, link in enumerate(self.query_links)}
        # parts: (row of its link in the link-state query, sphere centre, radius, body, link)
        rows, centres, radii, about_mass, self.parts = [], [], [], [], []
        for link in links:
            centre, radius = checker.spheres[link]
            rows.append(row[link])
            centres.append(centre)
            radii.append(radius)
            about_mass.append(checker.mass_spheres[link])
            self.parts.append((checker.link_names[link], self.body, link))
        for body, link, h, _ in self.held:
            ex, ey, ez = world.objects[h.name].extents
            rel = np.array(p.getMatrixFromQuaternion(h.relative[1])).reshape(3, 3)
            rows.append(row[link])
            centre = np.asarray(h.relative[0]) + rel @ np.array([0.0, 0.0, ez / 2])
            centres.append(centre)
            radii.append(0.5 * float(np.linalg.norm([ex, ey, ez])))
            about_mass.append(radii[-1] + float(np.linalg.norm(centre
                                                               - checker.mass_centre(link))))
            self.parts.append((repr(h.name), body, -1))
        self._rows = np.array(rows, dtype=int)
        self._row_list = rows  # (the list: indexing it in a state's broadphase is cheap)
        self._centres = np.array(centres, dtype=float).reshape(-1, 3)
        self._radii_sq = (np.array(radii, dtype=float) ** 2)[:, None]
        self._radius_max = max(radii, default=0.0)
        self._mass_radii_sq = np.array(about_mass, dtype=float) ** 2
        self._mass_radius_max = max(about_mass, default=0.0)
        held_names = {h.name for h in held}
        self.world = world
        # obstacles: every environment link with a shape, every item not held or ignored
        obstacles: list[tuple[int, int, str]] = []
        boxes = []
        for name, index, lo, hi in world.environment_link_boxes():
            if name not in ignore:
                obstacles.append((world.environment, index, name))
                boxes.append((lo, hi))
        for name, obj in world.objects.items():
            if name not in held_names and name not in ignore:
                obstacles.append((obj.body, -1, repr(name)))
                boxes.append(obj.aabb())
        self.obstacles = obstacles
        arr = np.array(boxes, dtype=float).reshape(-1, 2, 3)
        self._lo, self._hi = arr[:, 0, :].copy(), arr[:, 1, :].copy()
        #: Obstacles that are boxes turned about the vertical (a door swung open), by row:
        #: (centre, rotation, half extents). Their axis-aligned boxes cover far more than
        #: they do; spheres that reach into one are tested against the box itself.
        self._turned: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._env_rows = {index: row for row, (body, index, _) in enumerate(obstacles)
                          if body == world.environment}
        self._measure_turned([index for _, index in world.moving_environment_links()])
        self.checks = 0

    def _measure_turned(self, indices: Sequence[int]) -> None:
        for index in indices:
            row = self._env_rows.get(index)
            if row is None:
                continue
            box = self.world.turned_box(index)
            if box is None:
                self._turned.pop(row, None)
            else:
                self._turned[row] = box

    def _outside_turned(self, near: np.ndarray, centres: np.ndarray,
                        radii_sq: np.ndarray) -> None:
        """Clear the entries of `near` (spheres x obstacles) whose sphere (centres, squared
        radii per row) reaches into a turned obstacle's axis-aligned box but not into the
        box itself."""
        for row, (centre, rotation, half) in self._turned.items():
            hits = np.flatnonzero(near[:, row])
            if not len(hits):
                continue
            local = (centres[hits] - centre) @ rotation  # in the box's frame
            gap = np.maximum(np.abs(local) - half, 0.0)
            near[hits, row] = (gap * gap).sum(axis=1) < radii_sq[hits]

    def refresh_obstacles(self, joint: str) -> None:
        """Measure again the boxes of what a drawer's or door's joint moves (its links)
        and of the items (those inside ride along), keeping everything else."""
        world, moved = self.world, self.world.links_moved_by(joint)
        for row, (body, index, _) in enumerate(self.obstacles):
            if body == world.environment:
                if index in moved:
                    self._lo[row], self._hi[row] = world.link_bounds(index)
            else:
                self._lo[row], self._hi[row] = p.getAABB(body, -1,
                                                         physicsClientId=self.client)
        self._measure_turned(sorted(moved))

    def set_state(self, q: Sequence[float]) -> None:
        """Put the robot's moving joints at q (held objects follow in `_place_held`)."""
        p.resetJointStatesMultiDof(self.body, self.joint_indices, [[float(v)] for v in q],
                                   physicsClientId=self.client)

    def _place_held(self) -> None:
        for body, link, _, relative in self.held:
            state = p.getLinkState(self.body, link, computeForwardKinematics=True,
                                   physicsClientId=self.client)
            pos, orn = p.multiplyTransforms(state[4], state[5], *relative)
            p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=self.client)

    def _link_frames(self) -> tuple[list, list]:
        states = p.getLinkStates(self.body, self.query_links, computeForwardKinematics=True,
                                 physicsClientId=self.client)
        return [s[4] for s in states], [s[5] for s in states]

    def _overlaps(self, positions: np.ndarray, orientations: np.ndarray) -> np.ndarray:
        """Broadphase for S states at once: positions (S x links x 3) and orientations
        (S x links x 4 quaternions, or S x links x 3 x 3 rotation matrices) of the queried
        links -> mask (S x parts x obstacles) of the part spheres that reach into
        obstacle boxes."""
        s = len(positions)
        pos = positions[:, self._rows].reshape(-1, 3)
        if orientations.ndim == 4:
            rot = orientations[:, self._rows].reshape(-1, 3, 3)
            centres = pos + (rot @ np.tile(self._centres, (s, 1))[:, :, None])[:, :, 0]
        else:
            orn = orientations[:, self._rows].reshape(-1, 4)
            centres = pos + rotate(orn, np.tile(self._centres, (s, 1)))
        # only the obstacles that meet the box around every sphere can be near one
        reach = self._radius_max
        low, high = centres.min(axis=0) - reach, centres.max(axis=0) + reach
        close = np.flatnonzero(np.all((self._lo <= high) & (self._hi >= low), axis=1))
        near = np.zeros((s * len(self._rows), len(self._lo)), dtype=bool)
        if len(close):
            c = centres[:, None, :]
            gap = np.maximum(np.maximum(self._lo[close] - c, c - self._hi[close]), 0.0)
            radii_sq = np.tile(self._radii_sq, (s, 1))
            near[:, close] = (gap * gap).sum(axis=2) < radii_sq
            self._outside_turned(near, centres, radii_sq[:, 0])
        return near.reshape(s, len(self._rows), len(self._lo))

    def _pairs(self) -> np.ndarray:
        """(part, obstacle) index pairs whose sphere about the part's link's centre of
        mass overlaps the obstacle's box: the broadphase of one state (no rotation, few
        numpy calls; the spheres are a little larger than `_overlaps`', and the exact
        check of a pair costs less than the calls saved)."""
        if not len(self._rows):
            return np.zeros((0, 2), dtype=int)
        states = p.getLinkStates(self.body, self.query_links, computeForwardKinematics=True,
                                 physicsClientId=self.client)
        centres = np.array([states[r][0] for r in self._row_list])
        reach = self._mass_radius_max
        low, high = centres.min(axis=0) - reach, centres.max(axis=0) + reach
        close = np.flatnonzero(np.all((self._lo <= high) & (self._hi >= low), axis=1))
        if not len(close):
            return np.zeros((0, 2), dtype=int)
        c = centres[:, None, :]
        gap = np.maximum(np.maximum(self._lo[close] - c, c - self._hi[close]), 0.0)
        near = np.zeros((len(centres), len(self._lo)), dtype=bool)
        near[:, close] = np.einsum("pok,pok->po", gap, gap) < self._mass_radii_sq[:, None]
        if self._turned:
            self._outside_turned(near, centres, self._mass_radii_sq)
        return np.argwhere(near)

    def states_free(self, states: np.ndarray, order: Sequence[int] | None = None) -> bool:
        """Every state (rows of joint vectors) free: one broadphase for all of them, then
        exact checks of the states that need one, in `order` (default: as given)."""
        self.checks += len(states)
        if not len(states) or not len(self._rows):
            return True
        frames = self.checker.link_frames().frames(self.joints, np.asarray(states),
                                                   self.query_links)
        if frames is None:  # (Pinocchio cannot say: PyBullet, state by state)
            positions, orientations = [], []
            for q in states:
                self.set_state(q)
                pos, orn = self._link_frames()
                positions.append(pos)
                orientations.append(orn)
            frames = np.array(positions), np.array(orientations)
        near = self._overlaps(*frames)
        flagged = set(np.flatnonzero(near.any(axis=(1, 2))).tolist())
        for i in (order if order is not None else range(len(states))):
            if i not in flagged:
                continue
            self.set_state(states[i])
            if self.held:
                self._place_held()
            for part, k in np.argwhere(near[i]):
                if self._depth(int(part), int(k)) > self.tolerance_m:
                    return False
        return True

    def _depth(self, part: int, k: int) -> float:
        _, body, link = self.parts[part]
        other, other_link, _ = self.obstacles[k]
        points = p.getClosestPoints(body, other, 0.0, linkIndexA=link, linkIndexB=other_link,
                                    physicsClientId=self.client)
        return max((-pt[8] for pt in points), default=0.0)

    def is_free(self, q: Sequence[float], margin_m: float = 0.0) -> bool:
        """No penetration deeper than the tolerance (less `margin_m`) at joint vector q
        (left set)."""
        self.checks += 1
        self.set_state(q)
        pairs = self._pairs()
        if not len(pairs):
            return True
        if self.held:
            self._place_held()
        limit = self.tolerance_m - margin_m
        return all(self._depth(int(i), int(k)) <= limit for i, k in pairs)

    def contacts(self, q: Sequence[float] | None = None) -> list[Contact]:
        """Every penetration deeper than the tolerance (at q, or where the robot is)."""
        if q is not None:
            self.set_state(q)
        self._place_held()
        out = []
        for i, k in self._pairs():
            depth = self._depth(int(i), int(k))
            if depth > self.tolerance_m:
                out.append(Contact(self.parts[i][0], self.obstacles[k][2], depth))
        return sorted(out, key=lambda c: -c.depth_m)

    def current(self) -> np.ndarray:
        """The moving joints' current values."""
        states = p.getJointStates(self.body, self.joint_indices, physicsClientId=self.client)
        return np.array([s[0] for s in states])
