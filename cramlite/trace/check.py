"""`replay --check`: is anything inside anything, anywhere along a trace?

An independent re-check of what was executed, not the planner's collision path: the
planner asks coal whether surfaces cross (`cramlite.scene.collision`); this check
measures volumes. Every shape (the PR2's real collision meshes, the kitchen's and the
items' primitives) is covered with surface points about `SPACING_M` apart; the
penetration of two shapes is the deepest point of either that lies inside the other
(a box or cylinder by its exact signed distance; a mesh by the generalised winding
number, with the point's distance to the mesh's triangles as its depth). It sees a shape
wholly inside another (a fingertip inside the shoulder's housing) as deep as it is, and
it needs no simulator.

Checked at every state and `substeps - 1` points between consecutive states (held items
follow their gripper there): each robot link against the kitchen, the items (but the one
the action in progress manipulates, and a handle in the hand) and the robot's other
links (the SRDF's disabled pairs and links fixed to one another excepted); each held
item against the kitchen, the other items and the robot (its own gripper aside); each
standing item wherever it moved, against the kitchen and the other items; each drawer or
door wherever it moved, against every item (one closing through an item that stands still).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from cramlite.scene.geometry import (
    PointGrid,
    depth_text,
    placed_bounds,
    point_triangle_distances,
    primitive_depth,
    surface_samples,
    triangle_samples,
    winding_numbers,
)
from cramlite.scene.models import BOX, MESH, Shape, item_model, kitchen_model, pr2_model
from cramlite.scene.scene import FLOOR_LINK
from cramlite.scene.transforms import inverse, planar, pose_matrix
from cramlite.trace.format import Trace, TraceError, trace_setup
from cramlite.world.containers import load_containers
from cramlite.world.setup import Setup

#: Spacing of the surface points by which penetration is measured.
SPACING_M = 0.007
#: Points inside a mesh are first told by the voxel they fall in (its centre's winding
#: number and depth, computed once per voxel and kept): this voxel's side.
VOXEL_M = 0.005
VOXEL_HALF_DIAGONAL_M = VOXEL_M * math.sqrt(3) / 2


@dataclass(frozen=True)
class Penetration:
    """The deepest penetration found between two things along a trace."""

    what: str
    other: str
    depth_m: float
    t: float
    line: int  #: the trace line of the state (or the motion that starts there)
    between: bool = False  #: found on the motion from that line's state to the next

    def describe(self) -> str:
        where = f"between lines {self.line} and {self.line + 1}" if self.between \
            else f"line {self.line}"
        return (f"{self.what} {depth_text(self.depth_m)} inside {self.other} at t = "
                f"{self.t:.2f} s ({where})")


class _Body:
    """A shape of the checked scene, and how to cover any part of its surface with points
    about `SPACING_M` apart: `dense` covers its faces, `sparse` only its corners and edges
    (a face of a large body pressing into a smaller one puts the smaller one's points
    inside it: the larger body's faces need no points of their own, its edges and corners
    do)."""

    def __init__(self, label: str, kind: str, owner: str, shape: Shape):
        self.label, self.kind, self.owner, self.shape = label, kind, owner, shape
        self.mesh = shape.kind == MESH
        #: how far its points are from its frame's origin, at most
        self.reach = float(np.linalg.norm(shape.centre) + shape.radius)
        if self.mesh:
            from scipy.spatial import ConvexHull

            tri = shape.vertices[shape.triangles]
            self._dense = PointGrid(triangle_samples(tri, SPACING_M))
            edges = {tuple(sorted(e)) for t in shape.triangles.tolist()
                     for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
            self._sparse = PointGrid(np.vstack([shape.vertices] + [
                _segment_points(shape.vertices[a], shape.vertices[b]) for a, b in edges]))
            # a point outside the mesh's convex hull is outside the mesh: most points near
            # a mesh are told apart by its hull's planes, without the winding number
            equations = ConvexHull(shape.vertices).equations
            self.hull_normals, self.hull_offsets = equations[:, :3], equations[:, 3]
            self._voxels: dict[tuple[int, int, int], float] = {}
        elif shape.kind != BOX:
            self.points = surface_samples(shape, SPACING_M)

    def voxel_depths(self, local: np.ndarray) -> np.ndarray:
        """For points (mesh frame): how deep the centre of the voxel each falls in lies
        inside the mesh (negative: outside, by its distance), computed once per voxel. A
        point is at most a voxel's half diagonal from its voxel's centre, so it is no
        deeper than that depth plus the half diagonal."""
        keys = np.floor(local / VOXEL_M).astype(np.int64)
        unique, index = np.unique(keys, axis=0, return_inverse=True)
        missing = [k for k in map(tuple, unique.tolist()) if k not in self._voxels]
        if missing:
            centres = (np.array(missing, dtype=float) + 0.5) * VOXEL_M
            shape = self.shape
            inside = np.abs(winding_numbers(centres, shape.vertices, shape.triangles)) > 0.5
            distance = point_triangle_distances(centres, shape.vertices, shape.triangles)
            for key, is_in, d in zip(missing, inside, distance, strict=True):
                self._voxels[key] = float(d if is_in else -d)
        values = np.array([self._voxels[k] for k in map(tuple, unique.tolist())])
        return values[index.reshape(-1)]

    def points_within(self, lo: np.ndarray, hi: np.ndarray, dense: bool) -> np.ndarray:
        """Surface points (shape frame) inside the box lo..hi (shape frame): over its
        faces (`dense`), or on its edges and corners only."""
        shape = self.shape
        if self.mesh:
            return (self._dense if dense else self._sparse).within(lo, hi)
        if shape.kind == BOX:
            points = _box_points(shape.centre - shape.half, shape.centre + shape.half, lo, hi,
                                 dense)
        else:
            points = self.points
        keep = np.all((points >= lo - 1e-9) & (points <= hi + 1e-9), axis=1)
        return points[keep]


def _segment_points(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    n = max(1, int(math.ceil(np.linalg.norm(b - a) / SPACING_M)))
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


def _box_points(box_lo: np.ndarray, box_hi: np.ndarray, lo: np.ndarray,
                hi: np.ndarray, dense: bool = True) -> np.ndarray:
    """Points on the faces of a box (box_lo..box_hi) within lo..hi, SPACING_M apart (its
    edges and corners included; with `dense` False, only those)."""
    a, b = np.maximum(box_lo, lo), np.minimum(box_hi, hi)
    if np.any(a > b):
        return np.zeros((0, 3))
    axes = []
    for k in range(3):
        n = max(1, int(math.ceil((b[k] - a[k]) / SPACING_M)))
        axes.append(np.linspace(a[k], b[k], n + 1))
    out = []
    ends = (box_lo, box_hi)
    if not dense:  # the twelve edges: along axis k, at two ends of each other axis
        for k in range(3):
            m, n = [x for x in range(3) if x != k]
            for em in ends:
                for en in ends:
                    if a[m] - 1e-9 <= em[m] <= b[m] + 1e-9 and \
                            a[n] - 1e-9 <= en[n] <= b[n] + 1e-9:
                        line = np.zeros((len(axes[k]), 3))
                        line[:, k], line[:, m], line[:, n] = axes[k], em[m], en[n]
                        out.append(line)
        return np.vstack(out) if out else np.zeros((0, 3))
    for k in range(3):
        for side in (box_lo[k], box_hi[k]):
            if not a[k] - 1e-9 <= side <= b[k] + 1e-9:
                continue
            others = [axes[m] for m in range(3) if m != k]
            grid = np.stack(np.meshgrid(*others, indexing="ij"), axis=-1).reshape(-1, 2)
            face = np.insert(grid, k, side, axis=1)
            out.append(face)
    return np.vstack(out) if out else np.zeros((0, 3))


def _local_box(placement: np.ndarray, lo: np.ndarray, hi: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray]:
    """The bounds, in a shape's frame, of the world box lo..hi."""
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    local = (corners - placement[:3, 3]) @ placement[:3, :3]
    return local.min(axis=0), local.max(axis=0)


def depth_inside(points: np.ndarray, other: _Body, other_placement: np.ndarray,
                 tolerance_m: float) -> float:
    """How deep the deepest of `points` (world) lies inside `other` (m; 0: none inside):
    exact for a primitive; for a mesh exact where it may exceed `tolerance_m`, and below
    that within a voxel's half diagonal (see `_Body.voxel_depths`)."""
    if not len(points):
        return 0.0
    local = (points - other_placement[:3, 3]) @ other_placement[:3, :3]
    shape = other.shape
    box = np.all(np.abs(local - shape.centre) <= shape.half + 1e-9, axis=1)
    if not box.any():
        return 0.0
    local = local[box]
    if shape.kind != MESH:
        return float(primitive_depth(local, shape).max())
    local = local[np.all(local @ other.hull_normals.T + other.hull_offsets <= 1e-9, axis=1)]
    if not len(local):
        return 0.0
    estimate = other.voxel_depths(local)
    # a point whose voxel's centre is less deep than this cannot be deeper than the
    # tolerance, nor than the deepest voxel's points: it is not measured exactly
    floor = max(tolerance_m - VOXEL_HALF_DIAGONAL_M,
                float(estimate.max()) - 2 * VOXEL_HALF_DIAGONAL_M)
    maybe = local[estimate > floor]
    if not len(maybe):
        return float(max(0.0, estimate.max()))
    inside = np.abs(winding_numbers(maybe, shape.vertices, shape.triangles)) > 0.5
    if not inside.any():
        return float(max(0.0, min(estimate.max(), tolerance_m)))
    return float(point_triangle_distances(maybe[inside], shape.vertices,
                                          shape.triangles).max())


def penetration(a: _Body, pa: np.ndarray, b: _Body, pb: np.ndarray, lo: np.ndarray,
                hi: np.ndarray, tolerance_m: float) -> float:
    """How deep two placed bodies whose bounds meet in lo..hi (world) are inside each
    other (the deeper way round): the points of each within that box, inside the other
    (exact wherever it may exceed `tolerance_m`)."""
    out = 0.0
    small = a if a.shape.radius <= b.shape.radius else b
    for body, placement, other, other_placement in ((a, pa, b, pb), (b, pb, a, pa)):
        dense = body is small or other.shape.kind != MESH  # (a primitive's test is cheap)
        local = body.points_within(*_local_box(placement, lo, hi), dense)
        if len(local):
            world = local @ placement[:3, :3].T + placement[:3, 3]
            out = max(out, depth_inside(world, other, other_placement, tolerance_m))
    return out


@functools.cache
def _bodies(owner: str, kind: str, shape: Shape) -> _Body:
    """(The robot's and the kitchen's bodies are kept for the process: models are.)"""
    return _Body(owner, kind, owner, shape)


class TraceChecker:
    """Checks states of a trace of one setup."""

    def __init__(self, setup: Setup, joints: list[str], world_joints: list[str]):
        self.setup = setup
        self.robot = pr2_model()
        self.kitchen = kitchen_model(setup.world_urdf)
        self.containers = load_containers(setup.world_urdf)
        self.joints = joints
        self.world_joints = world_joints
        self.robot_bodies = [_bodies(link, "robot", shape) for link, shapes in
                             self.robot.shapes_by_link.items() for shape in shapes]
        self.kitchen_bodies = [_bodies(link, "kitchen", shape) for link, shapes in
                               self.kitchen.shapes_by_link.items() if link != FLOOR_LINK
                               for shape in shapes]
        self.items = {spec.name: item_model(spec.urdf, spec.type) for spec in setup.items}
        self.item_bodies = {name: [_Body(repr(name), "item", name, shape)
                                   for shape in model.shapes]
                            for name, model in self.items.items()}
        self.handles = {name: c.handle for name, c in self.containers.items()}
        self.grippers = {arm: {link for link in self.robot.link_frames
                               if f"{arm[0]}_wrist_roll_joint" in self.robot.joints_above(link)}
                         for arm in ("right", "left")}
        links = sorted(self.robot.shapes_by_link)
        self.self_pairs = {(a, b) for i, a in enumerate(links) for b in links[i + 1:]
                           if self.robot.may_collide(a, b)}
        self._moved_from: dict[str, np.ndarray] = {}
        self._swung_from: dict[str, np.ndarray] = {}  #: each kitchen link at the last state
        self._pair_cache: dict[tuple, np.ndarray] = {}
        #: (a's frame in b's, depth) of each pair of bodies when last measured
        self._measured: dict[tuple[int, int], tuple[np.ndarray, float]] = {}

    # -- placing everything -----------------------------------------------------------
    def robot_frames(self, state: dict[str, Any]) -> dict[str, np.ndarray]:
        values = self.robot.with_mimics(dict(zip(self.joints, state["q"], strict=True)))
        placements = self.robot.link_placements(values, list(self.robot.shapes_by_link) +
                                                [f"{a}_gripper_tool_frame" for a in "rl"])
        base = planar(*state["base"])
        return {link: base @ frame for link, frame in placements.items()}

    def kitchen_frames(self, state: dict[str, Any]) -> dict[str, np.ndarray]:
        return self.kitchen.link_placements(dict(zip(self.world_joints, state["w"],
                                                     strict=True)))

    def check(self, state: dict[str, Any], robot: dict[str, np.ndarray],
              item_frames: dict[str, np.ndarray], tolerance_m: float = 0.01,
              ) -> Iterator[tuple[str, str, float]]:
        """(what, other, depth) of every pair that meets at one state (positions given),
        its depth exact wherever it may exceed `tolerance_m`."""
        kitchen = self.kitchen_frames(state)
        held = state["held"]
        action = state.get("action") or {}
        manipulated = action.get("object")
        gripped = self.handles.get(manipulated)
        bodies: list[_Body] = []
        placements: list[np.ndarray] = []
        for body in self.robot_bodies:
            bodies.append(body)
            placements.append(robot[body.owner] @ body.shape.in_link)
        for body in self.kitchen_bodies:
            if body.owner != gripped:
                bodies.append(body)
                placements.append(kitchen[body.owner] @ body.shape.in_link)
        for name, item in self.item_bodies.items():
            if name in item_frames:
                for body in item:
                    bodies.append(body)
                    placements.append(item_frames[name] @ body.shape.in_link)
        placed = np.array(placements)
        lo, hi = placed_bounds([b.shape for b in bodies], placed)
        pairs = self._pairs(bodies, held, manipulated, item_frames, kitchen)
        if not len(pairs):
            return
        a, b = pairs[:, 0], pairs[:, 1]
        low, high = np.maximum(lo[a], lo[b]), np.minimum(hi[a], hi[b])
        meet = np.flatnonzero(np.all(low <= high, axis=1))
        for k in meet:
            i, j = a[k], b[k]
            if self._still_shallow(bodies[i], placed[i], bodies[j], placed[j], tolerance_m):
                continue
            depth = penetration(bodies[i], placed[i], bodies[j], placed[j], low[k], high[k],
                                tolerance_m)
            self._measured[(id(bodies[i]), id(bodies[j]))] = (
                inverse(placed[j]) @ placed[i], depth)
            yield bodies[i].label, bodies[j].label, depth

    def _still_shallow(self, a: _Body, pa: np.ndarray, b: _Body, pb: np.ndarray,
                       tolerance_m: float) -> bool:
        """Can two bodies not be deeper than the tolerance yet, by how little they have
        moved against each other since they were last measured? A point of either moves
        by at most |dt| + |dR| r against the other (r: how far the body's points are
        from its frame's origin), and depth changes by no more than the points move."""
        last = self._measured.get((id(a), id(b)))
        if last is None:
            return False
        relative = inverse(pb) @ pa
        before, depth = last
        change = relative - before
        turn = float(np.linalg.norm(change[:3, :3]))
        reach = max(a.reach, b.reach + float(np.linalg.norm(relative[:3, 3])))
        moved = float(np.linalg.norm(change[:3, 3])) + turn * reach
        return depth + moved < tolerance_m - 1e-6

    def _pairs(self, bodies: list[_Body], held: dict[str, str], manipulated: str | None,
               item_frames: dict[str, np.ndarray],
               kitchen: dict[str, np.ndarray]) -> np.ndarray:
        """The pairs of bodies (indices) checked at a state: see the module's doc."""
        out = []
        standing = [n for n in item_frames if n not in held]
        moved = set()
        for name in standing:  # an item standing somewhere: checked where it moved
            last = self._moved_from.get(name)
            if last is None or np.abs(item_frames[name] - last).max() >= 1e-3:
                self._moved_from[name] = item_frames[name].copy()
                moved.add(name)
        swung = set()  # a drawer or door that moved: checked against every item
        for link, frame in kitchen.items():
            last = self._swung_from.get(link)
            if last is not None and np.abs(frame - last).max() >= 1e-4:
                swung.add(link)
            self._swung_from[link] = frame
        key = (tuple(id(b) for b in bodies), tuple(sorted(held.items())), manipulated,
               frozenset(moved), frozenset(swung))
        if key not in self._pair_cache:
            if len(self._pair_cache) > 256:
                self._pair_cache.clear()
            for i, a in enumerate(bodies):
                for j in range(i + 1, len(bodies)):
                    if self._checked(a, bodies[j], held, manipulated, moved, swung):
                        out.append((i, j))
            self._pair_cache[key] = np.array(out, dtype=int).reshape(-1, 2)
        return self._pair_cache[key]

    def _checked(self, a: _Body, b: _Body, held: dict[str, str], manipulated: str | None,
                 moved: set[str], swung: set[str]) -> bool:
        kinds = (a.kind, b.kind)
        if kinds == ("robot", "robot"):
            return (a.owner, b.owner) in self.self_pairs or (b.owner, a.owner) in self.self_pairs
        if kinds == ("kitchen", "kitchen"):
            return False
        if "robot" in kinds:
            other = b if a.kind == "robot" else a
            link = a if a.kind == "robot" else b
            if other.kind == "kitchen":
                return True
            if other.owner in held:  # a held item: not against its own gripper
                return link.owner not in self.grippers.get(held[other.owner], set())
            return other.owner != manipulated
        if "kitchen" in kinds:
            item, link = (b, a) if a.kind == "kitchen" else (a, b)
            return item.owner in held or item.owner in moved or link.owner in swung
        # two items: one held (not against the item manipulated), or one that moved
        if a.owner == b.owner:
            return False
        if a.owner in held or b.owner in held:
            other = b if a.owner in held else a
            return other.owner != manipulated
        return a.owner in moved or b.owner in moved


def checker_for(trace: Trace) -> TraceChecker:
    """A checker of the trace's setup (its header names it as `load_setup` accepts)."""
    setup = trace_setup(trace)
    robot = pr2_model()
    missing = [n for n in trace.header["joints"] if n not in robot.joints]
    world = kitchen_model(setup.world_urdf)
    missing += [n for n in trace.header["world_joints"] if n not in world.joints]
    if missing:
        raise TraceError(f"header fields joints/world_joints: no joint {missing[0]!r} in the "
                         "robot or the world", field="line 1")
    items = {spec.name for spec in setup.items}
    for line, state in enumerate(trace.states, start=2):
        unknown = [name for name in state["objects"] if name not in items]
        if unknown:
            raise TraceError(f"objects: {unknown[0]!r} is not an item of the setup "
                             f"{setup.name!r}", field=f"line {line}")
    return TraceChecker(setup, list(trace.header["joints"]), list(trace.header["world_joints"]))


def _item_frames(state: dict[str, Any]) -> dict[str, np.ndarray]:
    return {name: object_frame(pose) for name, pose in state["objects"].items()}


def object_frame(pose: list[float]) -> np.ndarray:
    """An object's recorded pose [x, y, z, qx, qy, qz, qw] as a matrix; a quaternion that
    is not of unit length is normalised (none at all: no turn), so a trace with one is
    still checked (`physics_findings` reports it as an impossible state)."""
    q = np.asarray(pose[3:], dtype=float)
    norm = float(np.linalg.norm(q))
    q = q / norm if norm > 1e-9 else np.array([0.0, 0.0, 0.0, 1.0])
    return pose_matrix(pose[:3], q)


def _interpolate(a: dict[str, Any], b: dict[str, Any], s: float) -> dict[str, Any]:
    base = [a["base"][0] + s * (b["base"][0] - a["base"][0]),
            a["base"][1] + s * (b["base"][1] - a["base"][1]),
            a["base"][2] + s * math.remainder(b["base"][2] - a["base"][2], 2 * math.pi)]
    q = [x + s * (y - x) for x, y in zip(a["q"], b["q"], strict=True)]
    w = [x + s * (y - x) for x, y in zip(a["w"], b["w"], strict=True)]
    objects = {}
    for name, pa in a["objects"].items():
        pb = b["objects"].get(name, pa)
        position = [x + s * (y - x) for x, y in zip(pa[:3], pb[:3], strict=True)]
        qa, qb = np.array(pa[3:]), np.array(pb[3:])
        if qa @ qb < 0:
            qb = -qb
        quat = qa + s * (qb - qa)
        norm = float(np.linalg.norm(quat))  # (zero for a zero quaternion: a finding)
        objects[name] = [*position, *(quat / norm if norm > 1e-9 else quat)]
    return {**a, "t": a["t"] + s * (b["t"] - a["t"]), "base": base, "q": q, "w": w,
            "objects": objects}


def penetrations(trace: Trace, tolerance_m: float = 0.01, substeps: int = 2,
                 ) -> list[Penetration]:
    """Every pair that penetrates deeper than `tolerance_m` somewhere along the trace
    (each state and `substeps - 1` interpolated points between consecutive states), with
    its deepest point; an empty list means nothing was inside anything."""
    checker = checker_for(trace)
    worst: dict[tuple[str, str], Penetration] = {}
    states = trace.states
    for i, state in enumerate(states):
        line = i + 2
        robot = checker.robot_frames(state)
        items = _item_frames(state)
        _note(worst, checker.check(state, robot, items, tolerance_m), state, line, False,
              tolerance_m)
        if i + 1 >= len(states):
            continue
        nxt = states[i + 1]
        # held items keep their pose in their gripper's frame between the two states
        relative = {name: inverse(robot[f"{arm[0]}_gripper_tool_frame"]) @ items[name]
                    for name, arm in state["held"].items() if name in items}
        for k in range(1, substeps):
            mid = _interpolate(state, nxt, k / substeps)
            mid_robot = checker.robot_frames(mid)
            mid_items = _item_frames(mid)
            for name, arm in state["held"].items():
                if name in relative:
                    mid_items[name] = mid_robot[f"{arm[0]}_gripper_tool_frame"] @ relative[name]
            _note(worst, checker.check(mid, mid_robot, mid_items, tolerance_m), mid, line, True,
                  tolerance_m)
    return sorted(worst.values(), key=lambda f: -f.depth_m)


def _note(worst: dict, found, state: dict[str, Any], line: int, between: bool,
          tolerance_m: float) -> None:
    for what, other, depth in found:
        key = (what, other)
        if depth > tolerance_m and (key not in worst or depth > worst[key].depth_m):
            worst[key] = Penetration(what, other, depth, state["t"], line, between)
