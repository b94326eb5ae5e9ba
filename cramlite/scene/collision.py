"""Is a robot configuration collision-free? Checked on the planning scene with coal.

A `MotionCheck` fixes what one motion query moves (a set of joints), what the grippers
hold, what the motion may touch (the item being grasped, a handle in the hand), and the
rest of the robot (its base pose, its other joints: e.g. a gripper open or closed). A
state is free when:

- no moving robot link is inside the kitchen or an item (real meshes against the
  kitchen's and items' primitives, `TOLERANCE_M` of penetration allowed for contacts such
  as an item standing on the surface it is put on);
- no moving robot link is inside another robot link (self-collision: every pair whose
  relative pose the motion changes and that the SRDF does not disable, no tolerance);
- no held item is inside the kitchen, another item or the robot (its own gripper's palm
  and fingers aside), and no moving link is inside what the other hand holds.

Broadphase, a few numpy calls for every state of a motion at once: each shape's bounds
(a box in its own frame) as an axis-aligned box in the world, against those of everything
that stands still and of the other moving shapes; the pairs that meet then as oriented
boxes (the face axes of the separating-axis test), which leaves about one pair in six
(an open door's turned box, a forearm across the counter's corner). Narrow
phase: coal's exact test on the real meshes. coal sees surfaces that cross; a shape wholly
inside a mesh (a fingertip inside the shoulder's housing) crosses none, so where a shape
could lie inside a mesh the winding number of one of its points decides
(`cramlite.scene.geometry`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import coal
import numpy as np

from cramlite.scene.geometry import (
    PointGrid,
    bounds_at,
    boxes_apart,
    convex_hull_planes,
    depth_text,
    inside_mesh,
    placed_bounds,
    point_triangle_distances,
    primitive_depth,
    surface_samples,
    winding_numbers,
)
from cramlite.scene.kinematics import BatchedFrames
from cramlite.scene.models import BOX, CYLINDER, MESH, Shape
from cramlite.scene.scene import PlanningScene, tool_frame
from cramlite.scene.transforms import planar, planar_many

#: Penetration allowed between the robot (or a held item) and the kitchen or an item at
#: the states a motion is checked at: contacts (an item put down stands on its surface; a
#: finger pad on the counter beside a spoon) are not collisions. The trace's check allows
#: 1 cm, along the motion between states too.
TOLERANCE_M = 0.006
#: Oriented bounds further apart than the margin by more than this hold shapes that
#: cannot touch (the slack keeps coal's own rounding on the safe side).
BOX_SLACK_M = 1e-5
#: A state is rejected by the tool frames' tilt alone (`MotionCheck._tips`) only when it
#: tips the item by more than this in the cosine (their products and every link's round
#: differently, by ~1e-16); closer calls are left to every link's frames.
TIP_SLACK = 1e-9
#: Spacing of the surface points by which a mesh's depth inside a primitive is measured.
SAMPLE_SPACING_M = 0.01
#: Those points, by shape (the models, and so their shapes, live for the process).
_SAMPLES: dict[int, PointGrid] = {}


@dataclass(frozen=True)
class HeldObject:
    """An item that moves with a gripper's tool frame."""

    name: str
    arm: str
    relative: np.ndarray  #: the item's frame in the tool frame (4 x 4)


@dataclass(frozen=True)
class Contact:
    """A penetration found by `MotionCheck.contacts` (for messages and tests)."""

    what: str  #: robot link or held item
    other: str  #: kitchen link, item or robot link
    depth_m: float

    def describe(self) -> str:
        return f"{self.what} {depth_text(self.depth_m)} inside {self.other}"


@dataclass(frozen=True)
class _Part:
    label: str
    shape: Shape
    frame_link: str  #: the robot link whose frame carries it
    robot_link: str | None  #: the robot link it is (None: a held item)
    held: str | None  #: the held item it is
    held_arm: str | None  #: the gripper holding it (a held item)
    moving_joints: frozenset[str]  #: the moving joints that move it


@dataclass(frozen=True)
class _Obstacle:
    label: str
    shape: Shape
    kind: str  #: kitchen, item, robot or held
    owner: str  #: kitchen link, item name or robot link
    frame_link: str | None = None  #: the robot link carrying it (robot, held)


@dataclass(frozen=True)
class _Layout:
    """What one kind of query moves and checks (the same for every query that moves the
    same joints, holds the same items in the same hands and may touch the same things):
    its parts, its obstacles, which part-obstacle pairs and moving pairs it checks."""

    parts: tuple[_Part, ...]
    obstacles: tuple[_Obstacle, ...]
    links: tuple[str, ...]  #: the robot links carrying the parts
    rows: np.ndarray  #: each part's row in `links`
    allowed: np.ndarray  #: parts x obstacles
    pairs: np.ndarray  #: k x 2 moving parts checked against each other
    static_links: tuple[str, ...]  #: the robot links carrying obstacles
    kitchen: slice  #: where the kitchen's shapes are among the obstacles
    #: Arrays of the obstacles (derived once per layout, for placing them per query):
    #: each one's shape frame in its link's (O x 4 x 4) and the point `enclosed` tests
    #: (O x 3, shape frame); the robot's and held items' obstacles with the row of the
    #: static link carrying them; the items' obstacles with their item's index in
    #: `item_names`; every obstacle that is not the kitchen's.
    in_link: np.ndarray
    refs: np.ndarray
    robot_obstacles: np.ndarray
    robot_links: np.ndarray
    held_obstacles: np.ndarray
    held_links: np.ndarray
    item_obstacles: np.ndarray
    item_index: np.ndarray
    item_names: tuple[str, ...]
    others: np.ndarray
    #: every obstacle's local bounds: centre and half sizes (O x 3, shape frame)
    centres: np.ndarray
    halves: np.ndarray


@dataclass(frozen=True)
class _ObstaclesByState:
    """The obstacles at each of S states where a drawer or door moves along them (what
    it carries riding along): placements (S x O x 4 x 4), axis-aligned bounds (S x O x 3,
    and laid out 3 x S x O for the broadphase) and oriented boxes' axes and centres."""

    placements: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    lo_t: np.ndarray
    hi_t: np.ndarray
    box_axes: np.ndarray
    box_centres: np.ndarray


def _transform(matrix: np.ndarray) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(matrix[:3, :3]),
                            np.ascontiguousarray(matrix[:3, 3]))


class SceneCollisions:
    """Builds motion checks on one planning scene; keeps what is derived from the models
    (surface samples and hulls of the meshes, the layouts of kinds of queries, the
    kitchen's placed shapes by the drawers' and doors' positions) for the scene's life."""

    def __init__(self, scene: PlanningScene, tolerance_m: float = TOLERANCE_M):
        self.scene = scene
        self.tolerance_m = tolerance_m
        self.frames = BatchedFrames(scene.robot)
        robot = scene.robot
        self.gripper_links = {arm: {link for link in robot.link_frames
                                    if f"{arm[0]}_wrist_roll_joint" in robot.joints_above(link)}
                              for arm in ("right", "left")}
        self._hulls: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._layouts: dict[tuple, _Layout] = {}
        self._kitchen: dict[tuple, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.request = coal.CollisionRequest()
        self._requests: dict[float, coal.CollisionRequest] = {}
        self._eroded: dict[tuple, coal.CollisionGeometry | None] = {}
        self._part_frames: dict[tuple, tuple[_Layout, tuple]] = {}
        self._above: dict[str, frozenset[str]] = {}
        self._link_pairs: tuple[dict[str, int], np.ndarray] | None = None

    def enclosed(self, a: Shape, pa: np.ndarray, b: Shape, pb: np.ndarray) -> bool:
        """Does one shape lie wholly inside the other, a mesh (no surfaces cross)? Then a
        point of the inner one lies inside the mesh: in its bounds, in its convex hull,
        and (the exact test, rarely reached) its winding number is 1."""
        for inner, pi, outer, po in ((a, pa, b, pb), (b, pb, a, pa)):
            if outer.kind != MESH or inner.radius >= outer.radius:
                continue
            point = _reference_point(inner)
            world = pi[:3, :3] @ point + pi[:3, 3]
            local = (world - po[:3, 3]) @ po[:3, :3]
            if np.any(np.abs(local - outer.centre) > outer.half):
                continue
            normals, offsets = self.hull(outer)
            if np.any(normals @ local + offsets > 1e-9):
                continue
            if inside_mesh(local[None], outer)[0]:
                return True
        return False

    def depth(self, a: Shape, pa: np.ndarray, b: Shape, pb: np.ndarray) -> float:
        """How deep two placed shapes are inside each other (m; 0 if they are apart or
        only touch): two primitives by coal's signed distance; a mesh in a primitive by
        the mesh's surface points inside it; two meshes by the surface points of each
        inside the other; a shape wholly inside a mesh by its surface points' distance from
        the mesh's surface."""
        result = coal.CollisionResult()
        coal.collide(a.geometry, _transform(pa), b.geometry, _transform(pb), self.request,
                     result)
        meshes = a.kind == MESH or b.kind == MESH
        if not result.isCollision():
            if meshes and self.enclosed(a, pa, b, pb):
                return max(_enclosure_depth(a, pa, b, pb), 1e-9)
            return 0.0
        if a.kind == MESH and b.kind == MESH:
            return _mesh_depth(self, a, pa, b, pb)
        if meshes:
            mesh, pm, prim, pp = (a, pa, b, pb) if a.kind == MESH else (b, pb, a, pa)
            points = self.samples_near(mesh, pm, prim, pp)
            deepest = 0.0
            if len(points):
                local = (points - pp[:3, 3]) @ pp[:3, :3]
                deepest = float(primitive_depth(local, prim).max())
            if float(np.min(prim.half)) > THIN_PRIMITIVE_M:
                return deepest
            # (a thin primitive, a wall, may pass through the mesh: its points inside)
            return max(deepest, _depth_in_mesh(self, prim, pp, mesh, pm))
        return _primitive_pair_depth(self, a, pa, b, pb)

    def hull(self, shape: Shape) -> tuple[np.ndarray, np.ndarray]:
        """The outward normals and offsets of a mesh's convex hull (inside: n.x + d <= 0)."""
        key = ("hull", id(shape))
        if key not in self._hulls:
            self._hulls[key] = convex_hull_planes(shape.vertices)
        return self._hulls[key]

    def samples_near(self, shape: Shape, placement: np.ndarray, other: Shape,
                     other_placement: np.ndarray) -> np.ndarray:
        """A mesh's surface points (world) within the bounds of another placed shape."""
        grid = _SAMPLES.get(id(shape))
        if grid is None:
            grid = _SAMPLES[id(shape)] = PointGrid(surface_samples(shape, SAMPLE_SPACING_M))
        centre = other_placement[:3, :3] @ other.centre + other_placement[:3, 3]
        span = np.abs(other_placement[:3, :3]) @ other.half
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        local = (centre + corners * span - placement[:3, 3]) @ placement[:3, :3]
        points = grid.within(local.min(axis=0), local.max(axis=0))
        return points @ placement[:3, :3].T + placement[:3, 3]

    def eroded(self, shape: Shape, by: float) -> coal.CollisionGeometry | None:
        """A box, cylinder or sphere shrunk by `by` on every side (None if nothing is
        left): the points deeper than `by` in the shape are the points inside it."""
        key = (id(shape), round(by, 9))
        if key not in self._eroded:
            half = shape.half - by
            if np.any(half <= 0):
                self._eroded[key] = None
            elif shape.kind == BOX:
                self._eroded[key] = coal.Box(*(2 * half))
            elif shape.kind == CYLINDER:
                self._eroded[key] = coal.Cylinder(float(half[0]), float(2 * half[2]))
            else:
                self._eroded[key] = coal.Sphere(float(half[0]))
        return self._eroded[key]

    def request_with(self, margin: float) -> coal.CollisionRequest:
        request = self._requests.get(margin)
        if request is None:
            request = self._requests[margin] = coal.CollisionRequest()
            request.security_margin = margin
        return request

    def check(self, joints: Sequence[str], held: Sequence[HeldObject] | None = None,
              ignore: Sequence[str] = (), base: tuple[float, float, float] | None = None,
              fixed: dict[str, float] | None = None,
              self_collision: bool = True) -> MotionCheck:
        """A check of motions of `joints` (held items: the scene's, unless given), allowed
        to touch `ignore` (items or kitchen links), the base at `base` and the robot's
        other joints as believed (or as `fixed` sets some of them). Without
        `self_collision`, the robot is checked against the kitchen and the items only (a
        check of the whole upper body at other base poses: it does not move itself)."""
        if held is None:
            held = [HeldObject(name, h.arm, h.relative)
                    for name, h in self.scene.held.items()]
        return MotionCheck(self, list(joints), list(held), frozenset(ignore), base,
                           fixed or {}, self_collision)

    def layout(self, joints: Sequence[str], held: Sequence[HeldObject],
               ignore: frozenset[str], self_collision: bool = True) -> _Layout:
        key = (frozenset(joints), tuple((h.name, h.arm) for h in held), ignore,
               self_collision)
        if key not in self._layouts:
            self._layouts[key] = self._make_layout(set(joints), held, ignore, self_collision)
        return self._layouts[key]

    def _make_layout(self, moving: set[str], held: Sequence[HeldObject],
                     ignore: frozenset[str], self_collision: bool) -> _Layout:
        scene, robot = self.scene, self.scene.robot
        parts: list[_Part] = []
        obstacles: list[_Obstacle] = []
        for link, shapes in robot.shapes_by_link.items():
            above = frozenset(moving & self._joints_above(link))
            for shape in shapes:
                if above:
                    parts.append(_Part(link, shape, link, link, None, None, above))
                else:
                    obstacles.append(_Obstacle(link, shape, "robot", link, link))
        for item in held:
            tool = tool_frame(item.arm)
            above = frozenset(moving & self._joints_above(tool))
            for shape in scene.items[item.name].model.shapes:
                if above:
                    parts.append(_Part(repr(item.name), shape, tool, None, item.name,
                                       item.arm, above))
                else:
                    obstacles.append(_Obstacle(repr(item.name), shape, "held", item.name,
                                               tool))
        first = len(obstacles)
        obstacles += [_Obstacle(s.link, s, "kitchen", s.link) for s in scene.kitchen.shapes]
        kitchen = slice(first, len(obstacles))
        held_names = {h.name for h in held}
        for name, item in scene.items.items():
            if name not in held_names:
                obstacles += [_Obstacle(repr(name), s, "item", name) for s in item.model.shapes]
        links = tuple(dict.fromkeys(p.frame_link for p in parts))
        rows = np.array([links.index(p.frame_link) for p in parts], dtype=int)
        arms = {h.name: h.arm for h in held}
        allowed = self._allowed(parts, obstacles, arms, ignore, self_collision)
        pairs = self._meeting_pairs(parts) if self_collision else np.zeros((0, 2), dtype=int)
        static = tuple(dict.fromkeys(o.frame_link for o in obstacles if o.frame_link))
        in_link = np.array([o.shape.in_link for o in obstacles]).reshape(-1, 4, 4)
        refs = np.array([_reference_point(o.shape) for o in obstacles]).reshape(-1, 3)
        robot_ob = [k for k, o in enumerate(obstacles) if o.kind == "robot"]
        held_ob = [k for k, o in enumerate(obstacles) if o.kind == "held"]
        item_ob = [k for k, o in enumerate(obstacles) if o.kind == "item"]
        item_names = tuple(dict.fromkeys(obstacles[k].owner for k in item_ob))
        others = [k for k in range(len(obstacles)) if not (kitchen.start <= k < kitchen.stop)]
        index = np.array  # (integer index arrays, possibly empty)
        return _Layout(tuple(parts), tuple(obstacles), links, rows, allowed, pairs, static,
                       kitchen, in_link, refs, index(robot_ob, dtype=int),
                       index([static.index(obstacles[k].frame_link) for k in robot_ob],
                             dtype=int),
                       index(held_ob, dtype=int),
                       index([static.index(obstacles[k].frame_link) for k in held_ob],
                             dtype=int),
                       index(item_ob, dtype=int),
                       index([item_names.index(obstacles[k].owner) for k in item_ob],
                             dtype=int),
                       item_names, index(others, dtype=int),
                       np.array([o.shape.centre for o in obstacles]).reshape(-1, 3),
                       np.array([o.shape.half for o in obstacles]).reshape(-1, 3))

    def parts_in_frames(self, layout: _Layout, held: Sequence[HeldObject],
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                   np.ndarray]:
        """For a layout's parts held as `held`: each shape's placement in the frame of the
        link carrying it, its bounds' centre there, half sizes, rotation there, and the
        point `enclosed` tests (kept per layout and held poses)."""
        relative = {h.name: h.relative for h in held}
        key = (id(layout), tuple((h.name, np.asarray(h.relative).tobytes()) for h in held))
        found = self._part_frames.get(key)
        if found is not None and found[0] is layout:
            return found[1]
        parts = layout.parts
        in_frame = np.array([relative[p.held] @ p.shape.in_link if p.held
                             else p.shape.in_link for p in parts]).reshape(-1, 4, 4)
        shapes = [p.shape for p in parts]
        centres = np.array([sh.centre for sh in shapes]).reshape(-1, 3)
        halves = np.array([sh.half for sh in shapes]).reshape(-1, 3)
        rotations = in_frame[:, :3, :3]
        centres = (rotations @ centres[:, :, None])[:, :, 0] + in_frame[:, :3, 3]
        refs = np.array([f[:3, :3] @ _reference_point(sh) + f[:3, 3]
                         for f, sh in zip(in_frame, shapes, strict=True)]).reshape(-1, 3)
        if len(self._part_frames) > 4096:
            self._part_frames.clear()
        value = (in_frame, centres, halves, rotations, refs)
        self._part_frames[key] = (layout, value)
        return value

    def _joints_above(self, link: str) -> frozenset[str]:
        """The moving joints between the root and a link (kept: asked per link per
        layout)."""
        above = self._above.get(link)
        if above is None:
            above = self._above[link] = frozenset(self.scene.robot.joints_above(link))
        return above

    def _allowed(self, parts: Sequence[_Part], obstacles: Sequence[_Obstacle],
                 arms: dict[str, str], ignore: frozenset[str],
                 self_collision: bool) -> np.ndarray:
        """Which part may touch which obstacle (parts x obstacles): `_may_touch` of every
        pair, column by column for the kitchen and the items (the same for every part)
        and a row a part for the robot's links (by the robot's pairs, kept)."""
        allowed = np.ones((len(parts), len(obstacles)), dtype=bool)
        robot_cols, held_cols = [], []
        for k, o in enumerate(obstacles):
            if o.kind == "robot":
                robot_cols.append(k)
            elif o.kind == "held":
                held_cols.append(k)
            elif o.owner in ignore:
                allowed[:, k] = False
        if not (robot_cols or held_cols) or not len(parts):
            return allowed
        if not self_collision:
            allowed[:, robot_cols + held_cols] = False
            return allowed
        index, pairs = self._robot_pairs()
        owners = [index[obstacles[k].owner] for k in robot_cols]
        for i, part in enumerate(parts):
            if part.robot_link is not None:
                allowed[i, robot_cols] = pairs[index[part.robot_link], owners]
            else:
                allowed[i, robot_cols] = [obstacles[k].owner not in
                                          self.gripper_links[part.held_arm]
                                          for k in robot_cols]
            for k in held_cols:
                allowed[i, k] = self._may_touch(part, obstacles[k], arms, ignore)
        return allowed

    def _robot_pairs(self) -> tuple[dict[str, int], np.ndarray]:
        """The robot's links with shapes (name -> index) and which pairs of them may
        collide (`ArticulatedModel.may_collide`), worked out once."""
        if self._link_pairs is None:
            robot = self.scene.robot
            links = list(robot.shapes_by_link)
            self._link_pairs = ({link: i for i, link in enumerate(links)},
                                np.array([[robot.may_collide(a, b) for b in links]
                                          for a in links],
                                         dtype=bool).reshape(len(links), len(links)))
        return self._link_pairs

    def _may_touch(self, part: _Part, obstacle: _Obstacle, arms: dict[str, str],
                   ignore: frozenset[str]) -> bool:
        if obstacle.owner in ignore and obstacle.kind in ("kitchen", "item"):
            return False
        if obstacle.kind == "robot":
            if part.robot_link is not None:
                return self.scene.robot.may_collide(part.robot_link, obstacle.owner)
            return obstacle.owner not in self.gripper_links[part.held_arm]
        if obstacle.kind == "held":
            return part.robot_link is None or \
                part.robot_link not in self.gripper_links[arms[obstacle.owner]]
        return True

    def _meeting_pairs(self, parts: Sequence[_Part]) -> np.ndarray:
        """The pairs (i < j, k x 2) of moving parts checked against each other, as one
        matrix: two robot links the SRDF allows, a held item and a link of another
        gripper than its own, two held items; never two parts the motion moves together
        (they never move apart)."""
        n = len(parts)
        index, robot_pairs = self._robot_pairs()
        links = [i for i, p in enumerate(parts) if p.robot_link is not None]
        items = [i for i, p in enumerate(parts) if p.robot_link is None]
        meet = np.zeros((n, n), dtype=bool)
        if links:
            rows = [index[parts[i].robot_link] for i in links]
            meet[np.ix_(links, links)] = robot_pairs[np.ix_(rows, rows)]
        for i in items:
            grip = self.gripper_links[parts[i].held_arm]
            meet[i, links] = meet[links, i] = [parts[j].robot_link not in grip for j in links]
            meet[i, items] = True
        groups = {}
        together = np.array([groups.setdefault(p.moving_joints, len(groups)) for p in parts])
        meet &= together[:, None] != together[None, :]
        return np.argwhere(np.triu(meet, 1)).astype(int).reshape(-1, 2)

    def kitchen_block(self, world_joints: dict[str, float],
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The kitchen's shapes placed (K x 4 x 4) and their bounds, with the
        drawers and doors at `world_joints` (kept by their values)."""
        key = tuple(round(world_joints[n], 9) for n in self.scene.kitchen.joints)
        block = self._kitchen.get(key)
        if block is None:
            if len(self._kitchen) > 512:
                self._kitchen.clear()
            frames = self.scene.kitchen_frames(world_joints)
            shapes = self.scene.kitchen.shapes
            placements = np.array([frames[s.link] @ s.in_link for s in shapes]).reshape(-1, 4, 4)
            block = self._kitchen[key] = (placements, *placed_bounds(shapes, placements))
        return block


class MotionCheck:
    """One motion query's collision problem: `is_free(q)`, `states_free(states)`."""

    def __init__(self, owner: SceneCollisions, joints: list[str], held: list[HeldObject],
                 ignore: frozenset[str], base: tuple[float, float, float] | None,
                 fixed: dict[str, float], self_collision: bool = True):
        scene = owner.scene
        self.owner = owner
        self.scene = scene
        self.joints = joints
        self.tolerance_m = owner.tolerance_m
        self.values = scene.robot.with_mimics({**scene.belief.joints, **fixed})
        self._q = scene.robot.q(self.values)  # (Pinocchio's configuration of them)
        self.base = tuple(base or scene.base)
        self.base_matrix = planar(*self.base)
        self.checks = 0
        #: exact (narrow-phase) pair tests made
        self.narrow = 0
        self.held = held
        layout = owner.layout(joints, held, ignore, self_collision)
        self.layout = layout
        self.parts = layout.parts
        self.obstacles = layout.obstacles
        self._rows = layout.rows
        self._allowed, self._pairs = layout.allowed, layout.pairs
        #: each part's placement, bounds' centre, half sizes and rotation in the frame of
        #: the link carrying it, and its point that `enclosed` tests
        (self._in_frame, self._centres, self._halves, self._rotations,
         self._refs) = owner.parts_in_frames(layout, held)
        #: the world frames (n x 4 x 4) of the robot links that do not move, in
        #: `layout.static_links`' order
        self._static = None
        if layout.static_links:
            frames = scene.robot.link_placements_at(self._q, list(layout.static_links))
            self._static = self.base_matrix @ np.array(list(frames.values()))
        #: upright held items that this motion moves: (frame row, the item's z axis in the
        #: tool frame, cos of the largest tilt allowed, name)
        self._upright = []
        #: each of those items' origin in its tool frame, and the lowest its origin may go
        #: (None: no floor; the arm planner sets one for its OMPL searches, so that a path
        #: does not swing the item far below both its ends)
        origins = []
        for h in held:
            kind = scene.items[h.name].model.kind
            if kind.upright and tool_frame(h.arm) in layout.links:
                self._upright.append((layout.links.index(tool_frame(h.arm)),
                                      np.asarray(h.relative)[:3, 2].copy(),
                                      math.cos(math.radians(kind.upright_tolerance_deg)),
                                      h.name))
                origins.append(np.asarray(h.relative)[:3, 3])
        self._upright_origins = np.array(origins, dtype=float).reshape(-1, 3)
        self.upright_floors: np.ndarray | None = None
        #: the rows and tool frames of those items' grippers, in `_upright`'s order, and a
        #: copy of the configuration for asking their tilt (`_tips`)
        self._upright_rows = [row for row, *_ in self._upright]
        self._upright_links = tuple(layout.links[row] for row in self._upright_rows)
        self._scratch_q = self._q.copy()
        self._world_joints = dict(scene.belief.world_joints)
        self._place_obstacles()

    def _place_obstacles(self) -> None:
        """Where every obstacle is (robot links and the other hand's item where the robot
        stands, the kitchen as its drawers and doors stand, the items as believed), with
        its bounds."""
        layout = self.layout
        placements = np.empty((len(self.obstacles), 4, 4))
        relative = {h.name: h.relative for h in self.held}
        kitchen_placed, kitchen_lo, kitchen_hi = self.owner.kitchen_block(self._world_joints)
        if len(layout.static_links):
            static = self._static
            if len(layout.robot_obstacles):
                placements[layout.robot_obstacles] = \
                    static[layout.robot_links] @ layout.in_link[layout.robot_obstacles]
            for k, row in zip(layout.held_obstacles.tolist(), layout.held_links.tolist(),
                              strict=True):
                placements[k] = static[row] @ relative[self.obstacles[k].owner] @ \
                    layout.in_link[k]
        if len(layout.item_obstacles):
            placements[layout.item_obstacles] = self._item_placements(
                [self._item_matrix(name) for name in layout.item_names])
        placements[layout.kitchen] = kitchen_placed
        others = layout.others.tolist()
        lo, hi = np.empty((len(self.obstacles), 3)), np.empty((len(self.obstacles), 3))
        lo[layout.kitchen], hi[layout.kitchen] = kitchen_lo, kitchen_hi
        if others:
            lo[others], hi[others] = bounds_at(layout.centres[others],
                                               layout.halves[others], placements[others])
        self._lo, self._hi = lo, hi
        self._lo_t, self._hi_t = np.ascontiguousarray(lo.T), np.ascontiguousarray(hi.T)
        # each obstacle's bounds as an oriented box (axes, centre; half sizes: the layout's)
        self._box_axes = placements[:, :3, :3]
        self._box_centres = (self._box_axes @ layout.centres[:, :, None])[:, :, 0] + \
            placements[:, :3, 3]
        self._for_exact_tests(placements, lo, hi)

    def _for_exact_tests(self, placements: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                         ) -> None:
        """The obstacles the exact tests (`_state_free`) use: their placements (and coal's
        transforms of them, made when first asked), bounds and the points `enclosed`
        tests, as plain floats for `_nested_test` (made when first asked too: most checks
        never make an exact test)."""
        self._placements, self._transforms = placements, {}
        self._exact_bounds, self._exact_lists = (lo, hi), None

    def _obstacle_lists(self) -> tuple[list, list, list]:
        """The obstacles' bounds (low, high) and the points `enclosed` tests, as lists."""
        if self._exact_lists is None:
            placements, (lo, hi) = self._placements, self._exact_bounds
            refs = (placements[:, :3, :3] @ self.layout.refs[:, :, None])[:, :, 0] + \
                placements[:, :3, 3]
            self._exact_lists = (lo.tolist(), hi.tolist(), refs.tolist())
        return self._exact_lists

    def _item_placements(self, poses: Sequence[np.ndarray]) -> np.ndarray:
        """The items' obstacles placed, given each item's frame (in `item_names` order)."""
        layout = self.layout
        return np.asarray(poses)[layout.item_index] @ layout.in_link[layout.item_obstacles]

    def _item_matrix(self, name: str) -> np.ndarray:
        return self._item_poses[name] if name in getattr(self, "_item_poses", {}) \
            else self.scene.item_matrix(name)

    def _obstacle_transform(self, k: int) -> coal.Transform3s:
        transform = self._transforms.get(k)
        if transform is None:
            transform = self._transforms[k] = _transform(self._placements[k])
        return transform

    def move_world_joint(self, joint: str, value: float) -> None:
        """The drawer or door at `value` in this check (what it carries, items inside a
        drawer included, moves with it), e.g. at each stage of opening it."""
        scene = self.scene
        with scene.world_joint_at(joint, value, carry=True):
            self._item_poses = {name: scene.item_matrix(name) for name in scene.items
                                if name not in scene.held}
            self._world_joints = dict(scene.belief.world_joints)
        self._place_obstacles()

    def states_free_as_joint_moves(self, joint: str, values: Sequence[float],
                                   states: np.ndarray) -> bool:
        """Every state free with the drawer or door `joint` at its own value in each (what
        it carries riding along): the answer of `move_world_joint(joint, values[i])` then
        `is_free(states[i])` for every i, as one batch (the links' frames and the
        broadphase of all the states at once; a handle's whole path is checked so). The
        check's own world is left as it was."""
        states = np.asarray(states, dtype=float).reshape(-1, len(self.joints))
        self.checks += len(states)
        if not len(states) or not len(self.parts):
            return True
        frames = self._link_frames(states)
        if not self._kept_upright(frames):
            return False
        moving = self._obstacles_by_state(joint, values)
        near, meets, boxes = self._near(frames, 0.0, moving)
        saved = (self._placements, self._exact_bounds, self._exact_lists, self._transforms)
        try:
            for i in np.flatnonzero(near.any(axis=(1, 2)) | meets.any(axis=1)).tolist():
                # (that state's world, for the exact tests)
                self._for_exact_tests(moving.placements[i], moving.lo[i], moving.hi[i])
                if not self._state_free(frames[i], near[i], meets[i], 0.0,
                                        tuple(b[i] for b in boxes)):
                    return False
            return True
        finally:
            (self._placements, self._exact_bounds, self._exact_lists,
             self._transforms) = saved

    def _obstacles_by_state(self, joint: str, values: Sequence[float]) -> _ObstaclesByState:
        """The obstacles with `joint` at each of `values`, as `move_world_joint` places
        them: the kitchen as its drawers and doors then stand, the items as they then lie
        (only those in a drawer that moves ride along); the robot's own links and the
        other hand's item do not move with it."""
        layout, scene = self.layout, self.scene
        count = len(values)
        placements = np.repeat(self._placements[None], count, axis=0)
        lo, hi = np.repeat(self._lo[None], count, axis=0), np.repeat(self._hi[None], count, axis=0)
        items = layout.item_obstacles
        carried = bool(len(items)) and bool(scene.riding_along(joint))
        if len(items) and not carried:  # (the items lie as believed now, in every state)
            placements[:, items] = self._item_placements(
                [scene.item_matrix(name) for name in layout.item_names])
            lo[:, items], hi[:, items] = bounds_at(layout.centres[items],
                                                   layout.halves[items], placements[0, items])
        for i, value in enumerate(values):
            placed, kitchen_lo, kitchen_hi = self.owner.kitchen_block(
                {**scene.belief.world_joints, joint: float(value)})
            placements[i, layout.kitchen] = placed
            lo[i, layout.kitchen], hi[i, layout.kitchen] = kitchen_lo, kitchen_hi
            if carried:
                with scene.world_joint_at(joint, float(value), carry=True):
                    poses = [scene.item_matrix(name) for name in layout.item_names]
                placements[i, items] = self._item_placements(poses)
                lo[i, items], hi[i, items] = bounds_at(layout.centres[items],
                                                       layout.halves[items],
                                                       placements[i, items])
        axes = placements[..., :3, :3]
        centres = (axes @ layout.centres[None, :, :, None])[..., 0] + placements[..., :3, 3]
        return _ObstaclesByState(placements, lo, hi, np.ascontiguousarray(lo.transpose(2, 0, 1)),
                                 np.ascontiguousarray(hi.transpose(2, 0, 1)), axes, centres)

    # -- states ---------------------------------------------------------------------------
    def _link_frames(self, states: np.ndarray) -> np.ndarray:
        """World frames (S x L x 4 x 4) of the links carrying the parts."""
        return self.owner.frames.frames(self.base_matrix, self._q, self.joints, states,
                                        self.layout.links)

    def _near(self, frames: np.ndarray, margin: float = 0.0,
              moving: _ObstaclesByState | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Broadphase for S states: (S x parts x obstacles) parts whose bounds meet an
        obstacle's, and (S x pairs) moving parts whose bounds meet; and the boxes (S x P x 3
        centres and half spans, axis-aligned) and the parts' frames (S x P x 4 x 4), for
        `_nested_test`. Bounds are first compared axis-aligned (each part's over all
        the states, then state by state), then the pairs that meet so as oriented boxes
        (most of them turn out apart: a narrow test each saved). `moving`: each state's own
        obstacle bounds (a drawer or door that moves along the states)."""
        s = len(frames)
        placed = frames[:, self._rows]  # S x P x 4 x 4
        rotations = placed[..., :3, :3]
        centres = (rotations @ self._centres[None, :, :, None])[..., 0] + placed[..., :3, 3]
        pad = max(0.0, margin)
        gap = pad + BOX_SLACK_M
        axes = rotations @ self._rotations  # S x P x 3 x 3: each part's bounds' axes
        spans = (np.abs(axes) @ self._halves[None, :, :, None])[..., 0] + pad  # S x P x 3
        near = np.zeros((s, len(self.parts), len(self.obstacles)), dtype=bool)
        # (comparisons laid out x, y, z first: numpy reduces a leading axis of three
        # several times faster than a trailing one)
        c_t, s_t = centres.transpose(2, 0, 1), spans.transpose(2, 0, 1)  # 3 x S x P
        lo_t, hi_t = self._lo_t, self._hi_t  # 3 x O
        box_axes, box_centres = self._box_axes, self._box_centres  # O x 3 x 3, O x 3
        if moving is not None:  # (the first pass against the bounds over all the states)
            lo_t, hi_t = moving.lo_t.min(axis=1), moving.hi_t.max(axis=1)
        if len(self.obstacles) and len(self.parts):
            # each part's bounds over all the states first: the obstacles each part can
            # meet at all (few), then those pairs state by state
            if s == 1:
                low, high = c_t[:, 0] - s_t[:, 0], c_t[:, 0] + s_t[:, 0]  # 3 x P
            else:
                low, high = (c_t - s_t).min(axis=1), (c_t + s_t).max(axis=1)
            may = ((lo_t[:, None, :] <= high[:, :, None]) &
                   (hi_t[:, None, :] >= low[:, :, None])).all(axis=0) & self._allowed
            p, k = np.nonzero(may)
            if len(p):
                if s == 1:
                    state = np.zeros(len(p), dtype=int)
                else:
                    c, h = c_t[:, :, p], s_t[:, :, p]  # 3 x S x M
                    if moving is None:
                        low_k, high_k = lo_t[:, None, k], hi_t[:, None, k]
                    else:
                        low_k, high_k = moving.lo_t[:, :, k], moving.hi_t[:, :, k]
                    state, m = np.nonzero(((low_k <= c + h) & (high_k >= c - h)).all(axis=0))
                    p, k = p[m], k[m]
                if moving is None:
                    k_axes, k_centres = box_axes[k], box_centres[k]
                else:
                    k_axes, k_centres = moving.box_axes[state, k], moving.box_centres[state, k]
                close = ~boxes_apart(axes[state, p], centres[state, p], self._halves[p],
                                     k_axes, k_centres, self.layout.halves[k], gap)
                near[state[close], p[close], k[close]] = True
        meets = np.zeros((s, len(self._pairs)), dtype=bool)
        if len(self._pairs):
            a, b = self._pairs[:, 0], self._pairs[:, 1]
            state, pair = np.nonzero((np.abs(c_t[:, :, a] - c_t[:, :, b]) <=
                                      s_t[:, :, a] + s_t[:, :, b]).all(axis=0))
            if len(state):
                a, b = a[pair], b[pair]
                close = ~boxes_apart(axes[state, a], centres[state, a], self._halves[a],
                                     axes[state, b], centres[state, b], self._halves[b], gap)
                meets[state[close], pair[close]] = True
        return near, meets, (centres, spans, placed)

    def _nested_test(self, boxes: tuple[np.ndarray, np.ndarray, np.ndarray],
                     ) -> tuple[Callable[[int, int], bool], Callable[[int, int], bool]]:
        """For one state's boxes (the parts' centres, half spans and frames): may a part
        and an obstacle, or two parts, lie one wholly inside the other? Only if the point
        of one that `enclosed` tests lies in the other's box (the parts' points placed
        here: most states need no exact test). (Plain floats: asked of a few pairs a
        state, where array operations cost more.)"""
        centres, spans, placed = boxes
        refs = ((placed[:, :3, :3] @ self._refs[:, :, None])[:, :, 0] +
                placed[:, :3, 3]).tolist()
        centres, spans = centres.tolist(), spans.tolist()
        lo, hi, obstacle_refs = self._obstacle_lists()

        def within(point: list[float], centre: list[float], span: list[float]) -> bool:
            return (abs(point[0] - centre[0]) <= span[0] and abs(point[1] - centre[1]) <= span[1]
                    and abs(point[2] - centre[2]) <= span[2])

        def part_obstacle(p: int, k: int) -> bool:
            ref, low, high = refs[p], lo[k], hi[k]
            return ((low[0] <= ref[0] <= high[0] and low[1] <= ref[1] <= high[1]
                     and low[2] <= ref[2] <= high[2])
                    or within(obstacle_refs[k], centres[p], spans[p]))

        def part_part(i: int, j: int) -> bool:
            return within(refs[i], centres[j], spans[j]) or within(refs[j], centres[i], spans[i])

        return part_obstacle, part_part

    def states_free(self, states: np.ndarray, order: Sequence[int] | None = None,
                    margin_m: float = 0.0) -> bool:
        """Every state (rows of joint vectors) free (keeping `margin_m` further away): one
        broadphase for all of them, then exact checks of the states that need one, in
        `order` (default: as given), up to the first that collides."""
        return self.first_collision(states, order, margin_m) is None

    def first_collision(self, states: np.ndarray, order: Sequence[int] | None = None,
                        margin_m: float = 0.0) -> int | None:
        """`states_free`, telling where in `order` the first state that collides (or tips
        an upright item) is: None if none does (how many states a check one by one in
        that order would have made)."""
        states = np.asarray(states, dtype=float).reshape(-1, len(self.joints))
        self.checks += len(states)
        if not len(states) or not len(self.parts):
            return None
        if len(states) == 1 and self._tips(states[0]):
            return 0  # (a motion's end, checked alone first: most such ends tip the item)
        return self._first_collision(self._link_frames(states), order, margin_m)

    def states_free_along(self, bases: np.ndarray, states: np.ndarray) -> bool:
        """`states_free` with the base at its own pose (x, y, yaw) in each state: a drive
        and a joint motion at once, checked as one."""
        states = np.asarray(states, dtype=float).reshape(-1, len(self.joints))
        self.checks += len(states)
        if not len(states) or not len(self.parts):
            return True
        saved = self.base_matrix
        self.base_matrix = np.eye(4)
        try:
            local = self._link_frames(states)  # (in the base's frame)
        finally:
            self.base_matrix = saved
        worlds = planar_many(bases)
        return self._first_collision(worlds[:, None] @ local, None) is None

    def _first_collision(self, frames: np.ndarray, order: Sequence[int] | None,
                         margin: float = 0.0) -> int | None:
        """`first_collision` on the links' world frames: the states that tip an upright
        item found at once, exact checks only before the first of them. States `order`
        leaves out are checked after those it names."""
        n = len(frames)
        if order is None:
            order = list(range(n))
        else:
            order = [int(i) for i in order]
            if len(order) != n or len(set(order)) != n:
                named = set(order)
                order += [i for i in range(n) if i not in named]
        upright = self._upright_states(frames)
        tipped = [] if upright is None else [pos for pos, i in enumerate(order)
                                             if not upright[i]]
        if tipped:
            order = order[:tipped[0]]  # (the states before it, then that one)
        if order:
            ordered = frames if order == list(range(n)) else frames[order]
            near, meets, boxes = self._near(ordered, margin)
            for pos in np.flatnonzero(near.any(axis=(1, 2)) | meets.any(axis=1)).tolist():
                if not self._state_free(ordered[pos], near[pos], meets[pos], margin,
                                        tuple(b[pos] for b in boxes)):
                    return pos
        return tipped[0] if tipped else None

    def is_free(self, q: Sequence[float], margin_m: float = 0.0) -> bool:
        """No penetration beyond what is allowed (keeping `margin_m` further away) at
        joint vector q."""
        self.checks += 1
        if not len(self.parts):
            return True
        q = np.asarray(q, dtype=float)
        if self._tips(q):
            return False
        frames = self._link_frames(q[None])
        if not self._kept_upright(frames):
            return False
        near, meets, boxes = self._near(frames, margin_m)
        if not near.any() and not meets.any():
            return True
        return self._state_free(frames[0], near[0], meets[0], margin_m,
                                tuple(b[0] for b in boxes))

    @property
    def moves_upright_items(self) -> bool:
        """Does this motion move an item that must stay upright?"""
        return bool(self._upright)

    def _tips(self, q: np.ndarray) -> bool:
        """Does state q surely tip an upright held item beyond its tilt? Asked of the tool
        frames' rotations alone, before every link is placed: most states OMPL samples for
        a motion holding such an item tip it. (Surely: by more than a rounding's worth, so
        that a state this passes gets the very answer `_kept_upright` gives it.)"""
        if not self._upright:
            return False
        rows = self.owner.frames.z_rows(self._scratch_q, self.joints, q, self._upright_links)
        return any(float(rows[k] @ axis) < cos_limit - TIP_SLACK
                   for k, (_, axis, cos_limit, _) in enumerate(self._upright))

    def _kept_upright(self, frames: np.ndarray) -> bool:
        """Every upright held item within its tilt at every state (S x L x 4 x 4)."""
        kept = self._upright_states(frames)
        return kept is None or bool(kept.all())

    def _upright_states(self, frames: np.ndarray) -> np.ndarray | None:
        """Which states (S x L x 4 x 4) keep every upright held item within its tilt
        (None: the motion moves none)."""
        if not self._upright:
            return None
        kept = np.ones(len(frames), dtype=bool)
        for row, axis, cos_limit, _ in self._upright:
            kept &= frames[:, row, 2, :3] @ axis >= cos_limit
        if self.upright_floors is not None:
            kept &= (self._heights(frames) >= self.upright_floors).all(axis=1)
        return kept

    def upright_heights(self, states: np.ndarray) -> np.ndarray:
        """The height of each upright held item's origin (S x U, `_upright`'s order) at
        each state (rows of joint vectors)."""
        states = np.asarray(states, dtype=float).reshape(-1, len(self.joints))
        return self._heights(self._link_frames(states))

    def _heights(self, frames: np.ndarray) -> np.ndarray:
        tools = frames[:, self._upright_rows]  # (S x U x 4 x 4)
        return np.einsum("suj,uj->su", tools[:, :, 2, :3], self._upright_origins) + \
            tools[:, :, 2, 3]

    def tilts(self, q: Sequence[float]) -> list[tuple[str, float]]:
        """(item, tilt in degrees) of every upright held item tilted beyond its limit at
        q (for messages)."""
        frames = self._link_frames(np.asarray(q, dtype=float)[None])
        out = []
        for row, axis, cos_limit, name in self._upright:
            cz = float(frames[0, row, 2, :3] @ axis)
            if cz < cos_limit:
                out.append((name, math.degrees(math.acos(max(-1.0, min(1.0, cz))))))
        return out

    def is_free_at(self, base: tuple[float, float, float], q: Sequence[float]) -> bool:
        """`is_free(q)` with the base at another pose (a check built without
        self-collision: the robot's own links stand still relative to one another)."""
        saved = self.base_matrix
        self.base_matrix = planar(*base)
        try:
            return self.is_free(q)
        finally:
            self.base_matrix = saved

    def _state_free(self, frames: np.ndarray, near: np.ndarray, meets: np.ndarray,
                    margin: float, boxes: tuple[np.ndarray, np.ndarray, np.ndarray]) -> bool:
        placed: dict[int, tuple[np.ndarray, coal.Transform3s]] = {}
        nesting: list = []  # (the test, made when first asked)

        def nested(kind: int, a: int, b: int) -> bool:
            if not nesting:
                nesting.extend(self._nested_test(boxes))
            return nesting[kind](a, b)

        def part(i: int) -> tuple[np.ndarray, coal.Transform3s]:
            if i not in placed:
                matrix = frames[self._rows[i]] @ self._in_frame[i]
                placed[i] = (matrix, _transform(matrix))
            return placed[i]

        for p, k in np.argwhere(near).tolist():
            pa, ta = part(p)
            if self._collides(self.parts[p].shape, pa, ta, self.obstacles[k].shape,
                              self._placements[k], self._obstacle_transform(k),
                              self._allowance(self.obstacles[k], self.parts[p]), margin,
                              lambda p=p, k=k: nested(0, p, k)):
                return False
        for i, j in self._pairs[np.flatnonzero(meets)].tolist():
            pa, ta = part(i)
            pb, tb = part(j)
            if self._collides(self.parts[i].shape, pa, ta, self.parts[j].shape, pb, tb,
                              self._allowance(None, self.parts[i], self.parts[j]), margin,
                              lambda i=i, j=j: nested(1, i, j)):
                return False
        return True

    def _collides(self, a: Shape, pa: np.ndarray, ta: coal.Transform3s, b: Shape,
                  pb: np.ndarray, tb: coal.Transform3s, allowance: float,
                  margin: float, nested: Callable[[], bool] = lambda: True) -> bool:
        """Are two placed shapes inside each other beyond what is allowed (keeping
        `margin` further apart)? `nested()`: may one lie wholly inside the other (a
        cheap necessary condition, asked before the exact `enclosed`)?"""
        owner = self.owner
        self.narrow += 1
        clearance = margin - allowance  # > 0: they must be this far apart
        meshes = a.kind == MESH or b.kind == MESH
        result = coal.CollisionResult()
        if clearance > 0 or not meshes:
            coal.collide(a.geometry, ta, b.geometry, tb, owner.request_with(clearance), result)
            if result.isCollision():
                return True
            return meshes and (nested() and owner.enclosed(a, pa, b, pb))
        limit = allowance - max(margin, 0.0)
        if limit <= 0 or (a.kind == MESH and b.kind == MESH):
            coal.collide(a.geometry, ta, b.geometry, tb, owner.request, result)
            return result.isCollision() or (nested() and owner.enclosed(a, pa, b, pb))
        # a mesh and a primitive, `limit` allowed: a surface point of the mesh is deeper
        # than that in the primitive exactly where the mesh meets the primitive shrunk by it
        prim_first = a.kind != MESH
        eroded = owner.eroded(a if prim_first else b, limit)
        if eroded is None:
            # a primitive thinner than twice the limit (a bowl's 6 mm wall): no point of the
            # mesh can be deeper in it than that, yet the wall may pass right through the
            # mesh (its own points deep inside): any contact counts
            coal.collide(a.geometry, ta, b.geometry, tb, owner.request, result)
            return result.isCollision() or (nested() and owner.enclosed(a, pa, b, pb))
        if prim_first:
            coal.collide(eroded, ta, b.geometry, tb, owner.request, result)
        else:
            coal.collide(a.geometry, ta, eroded, tb, owner.request, result)
        if result.isCollision():
            return True
        return (nested() and owner.enclosed(a, pa, b, pb))

    def _allowance(self, obstacle: _Obstacle | None, part: _Part,
                   other: _Part | None = None) -> float:
        """Penetration allowed: none between two robot links, `TOLERANCE_M` otherwise."""
        robot_pair = part.robot_link is not None and (
            (obstacle is not None and obstacle.kind == "robot") or
            (other is not None and other.robot_link is not None))
        return 0.0 if robot_pair else self.tolerance_m

    def _depth(self, a: Shape, pa: np.ndarray, b: Shape, pb: np.ndarray, allowance: float,
               margin: float) -> float:
        """How far beyond what is allowed two placed shapes are inside each other (> 0:
        a collision), measured (for messages)."""
        depth = self.owner.depth(a, pa, b, pb)
        limit = allowance - max(margin, 0.0)
        return depth - limit if depth > limit and depth > 0 else 0.0

    def contacts(self, q: Sequence[float] | None = None) -> list[Contact]:
        """Every penetration beyond what is allowed at q (or as the robot stands), with
        its depth, deepest first."""
        q = np.array([self.values[n] for n in self.joints]) if q is None else np.asarray(q)
        frames = self._link_frames(np.asarray(q, dtype=float)[None])[0]
        near, meets, _ = self._near(frames[None])
        out = []
        for p, k in np.argwhere(near[0]):
            part, obstacle = self.parts[p], self.obstacles[k]
            allowance = self._allowance(obstacle, part)
            depth = self._depth(part.shape, frames[self._rows[p]] @ self._in_frame[p],
                                obstacle.shape, self._placements[k], allowance, 0.0)
            if depth > 0:
                out.append(Contact(part.label, obstacle.label, depth + allowance))
        for n in np.flatnonzero(meets[0]):
            i, j = self._pairs[n]
            a, b = self.parts[i], self.parts[j]
            depth = self._depth(a.shape, frames[self._rows[i]] @ self._in_frame[i], b.shape,
                                frames[self._rows[j]] @ self._in_frame[j], 0.0, 0.0)
            if depth > 0:
                out.append(Contact(a.label, b.label, depth))
        return sorted(out, key=lambda c: -c.depth_m)

    def current(self) -> np.ndarray:
        """The moving joints' values as believed (or as `fixed` set them)."""
        return np.array([self.values[n] for n in self.joints])


def _reference_point(shape: Shape) -> np.ndarray:
    """The point of a shape (its frame) that `SceneCollisions.enclosed` tests."""
    return shape.vertices[0] if shape.kind == MESH else shape.centre


def _enclosure_depth(a: Shape, pa: np.ndarray, b: Shape, pb: np.ndarray) -> float:
    """How deep a shape wholly inside a mesh is: the largest distance of its surface points
    from the mesh's surface."""
    for inner, pi, outer, po in ((a, pa, b, pb), (b, pb, a, pa)):
        if outer.kind != MESH:
            continue
        points = surface_samples(inner, SAMPLE_SPACING_M) @ pi[:3, :3].T + pi[:3, 3]
        local = (points - po[:3, 3]) @ po[:3, :3]
        inside = inside_mesh(local, outer)
        if inside.any():
            return float(point_triangle_distances(local[inside], outer.vertices,
                                                  outer.triangles).max())
    return 0.0


def _mesh_depth(owner: SceneCollisions, a: Shape, pa: np.ndarray, b: Shape,
                pb: np.ndarray) -> float:
    """How deep two crossing meshes are inside each other: the largest distance from the
    other's surface of the surface points of one that lie inside the other."""
    return max(_depth_in_mesh(owner, a, pa, b, pb), _depth_in_mesh(owner, b, pb, a, pa))


#: A primitive this thin (half its smallest side) may pass through a mesh with no point of
#: the mesh deep inside it: its depth also counts its own points inside the mesh.
THIN_PRIMITIVE_M = 0.01


def _depth_in_mesh(owner: SceneCollisions, inner: Shape, pi: np.ndarray, outer: Shape,
                   po: np.ndarray) -> float:
    """The largest distance from a mesh's (`outer`) surface of the surface points of
    another shape that lie inside it."""
    points = owner.samples_near(inner, pi, outer, po)
    if not len(points):
        return 0.0
    local = (points - po[:3, 3]) @ po[:3, :3]
    box = np.all(np.abs(local - outer.centre) <= outer.half + 1e-9, axis=1)
    if not box.any():
        return 0.0
    candidates = local[box]
    inside = np.abs(winding_numbers(candidates, outer.vertices, outer.triangles)) > 0.5
    if not inside.any():
        return 0.0
    return float(point_triangle_distances(candidates[inside], outer.vertices,
                                          outer.triangles).max())


def _primitive_pair_depth(owner: SceneCollisions, a: Shape, pa: np.ndarray, b: Shape,
                          pb: np.ndarray) -> float:
    """How deep two primitives are inside each other (coal's signed distance)."""
    request = coal.DistanceRequest()
    result = coal.DistanceResult()
    coal.distance(a.geometry, _transform(pa), b.geometry, _transform(pb), request, result)
    return max(0.0, -float(result.min_distance))


__all__ = ["Contact", "HeldObject", "MotionCheck", "SceneCollisions", "TOLERANCE_M"]
