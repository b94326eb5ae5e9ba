"""Kinematic and collision models of the robot, the kitchen and the items, from URDFs.

Pinocchio reads each URDF (`buildModelFromUrdf`, fixed root) and its collision geometry
(`buildGeomFromUrdf`: coal boxes, cylinders and spheres, and meshes as coal BVH models of
their real triangles); nothing here simulates anything. A model is immutable and built
once per process and file (they are pure functions of the file); the state of the scene
(where the robot stands, its joints, the drawers, the items) lives in `PlanningScene`.

Every shape is kept by the link it belongs to, with its placement in that link's frame,
its local bounds and bounding sphere (the broadphase) and, for a mesh, its vertices and
triangles (outlines seen from above, and the test that one mesh lies wholly inside
another, which coal's surface-crossing test cannot see).
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from cramlite.digests import file_digest  # noqa: F401  (re-exported)
from cramlite.world.item_types import ItemType, item_type, item_type_file
from cramlite.world.pr2 import PR2_URDF_SUBPATH, pr2_share_folder

#: The kinds of shapes a link can have.
BOX, CYLINDER, SPHERE, MESH = "box", "cylinder", "sphere", "mesh"


@dataclass(frozen=True, eq=False)
class Shape:
    """One collision geometry of a link."""

    name: str  #: the geometry's name (pinocchio's: LINK_N)
    link: str
    kind: str  #: box, cylinder, sphere or mesh
    geometry: coal.CollisionGeometry
    in_link: np.ndarray  #: 4 x 4 placement of the shape's frame in the link's frame
    #: Half extents of the shape's local bounds and their centre (shape frame): for a box
    #: its half sizes; a cylinder (axis z) r, r, h/2; a sphere r, r, r; a mesh its bounds.
    half: np.ndarray
    centre: np.ndarray
    radius: float  #: of a sphere about `centre` that holds the shape
    vertices: np.ndarray | None = None  #: a mesh's vertices (shape frame)
    triangles: np.ndarray | None = None  #: a mesh's triangles (vertex indices)

    @property
    def size(self) -> tuple[float, ...]:
        """Box: full sizes; cylinder: radius, length; sphere: radius; mesh: bounds."""
        if self.kind == CYLINDER:
            return (float(self.half[0]), float(2 * self.half[2]))
        if self.kind == SPHERE:
            return (float(self.half[0]),)
        return tuple(float(2 * h) for h in self.half)


def _shape(go, link: str, in_link: np.ndarray) -> Shape:
    geometry = go.geometry
    vertices = triangles = None
    if isinstance(geometry, coal.Box):
        kind, half = BOX, np.asarray(geometry.halfSide, dtype=float).copy()
        centre = np.zeros(3)
    elif isinstance(geometry, coal.Cylinder):
        kind = CYLINDER
        half = np.array([geometry.radius, geometry.radius, geometry.halfLength])
        centre = np.zeros(3)
    elif isinstance(geometry, coal.Sphere):
        kind, half, centre = SPHERE, np.full(3, geometry.radius), np.zeros(3)
    elif hasattr(geometry, "num_tris"):
        kind = MESH
        vertices = np.array(geometry.vertices(), dtype=float).reshape(-1, 3)
        triangles = np.array([[t[0], t[1], t[2]] for t in
                              (geometry.tri_indices(i) for i in range(geometry.num_tris))],
                             dtype=np.int64).reshape(-1, 3)
        lo, hi = vertices.min(axis=0), vertices.max(axis=0)
        centre, half = (lo + hi) / 2, (hi - lo) / 2
    else:
        raise ValueError(f"{go.name}: collision geometry {type(geometry).__name__} is not "
                         "supported; expected a box, cylinder, sphere or mesh")
    if vertices is not None:
        radius = float(np.linalg.norm(vertices - centre, axis=1).max())
    else:
        radius = float(np.linalg.norm(half)) if kind != SPHERE else float(half[0])
        if kind == CYLINDER:
            radius = float(math.hypot(half[0], half[2]))
    return Shape(go.name, link, kind, geometry, in_link, half, centre, radius, vertices,
                 triangles)


@dataclass(frozen=True)
class JointInfo:
    name: str
    kind: str  #: "revolute", "continuous" or "prismatic"
    q_index: int
    lower: float
    upper: float
    velocity: float
    axis: np.ndarray  #: in the joint's frame


class ArticulatedModel:
    """A URDF's kinematic tree (fixed root) and collision shapes, by link and joint name."""

    def __init__(self, urdf: Path, package_dirs: list[str] | None = None):
        self.urdf = Path(urdf)
        self.package_dirs = list(package_dirs or [])
        self.model = pin.buildModelFromUrdf(str(urdf))
        geometry = pin.buildGeomFromUrdf(self.model, str(urdf), pin.GeometryType.COLLISION,
                                         package_dirs=package_dirs or [])
        self.geometry_model = geometry
        model = self.model
        #: link name -> pinocchio frame id (the link's own frame)
        self.link_frames: dict[str, int] = {
            f.name: i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY}
        #: joint name -> JointInfo (moving joints)
        self.joints: dict[str, JointInfo] = {}
        for jid in range(1, model.njoints):
            joint = model.joints[jid]
            name = model.names[jid]
            short = joint.shortname()
            iq = int(model.idx_qs[jid])
            if joint.nq == 2:  # a continuous joint: cos, sin
                kind, lower, upper = "continuous", -math.inf, math.inf
            else:
                kind = "prismatic" if short.replace("JointModel", "").startswith("P") \
                    else "revolute"
                lower = float(model.lowerPositionLimit[iq])
                upper = float(model.upperPositionLimit[iq])
            self.joints[name] = JointInfo(name, kind, iq, lower, upper,
                                          float(model.velocityLimit[int(model.idx_vs[jid])]),
                                          _axis(joint))
        # (in the order the URDF lists them, as simulators number them: traces list them)
        listed = [j.get("name") for j in ET.parse(urdf).getroot().iter("joint")]
        self.joints = dict(sorted(self.joints.items(),
                                  key=lambda kv: listed.index(kv[0]) if kv[0] in listed
                                  else len(listed)))
        self.shapes: list[Shape] = []
        for go in geometry.geometryObjects:
            frame = model.frames[go.parentFrame]
            in_link = frame.placement.actInv(go.placement).homogeneous
            self.shapes.append(_shape(go, frame.name, in_link))
        self.shapes_by_link: dict[str, list[Shape]] = {}
        for shape in self.shapes:
            self.shapes_by_link.setdefault(shape.link, []).append(shape)

    @property
    def joint_names(self) -> list[str]:
        return list(self.joints)

    def q(self, values: dict[str, float]) -> np.ndarray:
        """Pinocchio's configuration from joint values by name (others: zero)."""
        neutral, slots = self._q_slots
        q = list(neutral)  # (a list, filled, then one array: item by item costs more)
        for name, value in values.items():
            slot = slots.get(name)
            if slot is None:
                continue
            i, continuous = slot
            if continuous:
                q[i], q[i + 1] = math.cos(value), math.sin(value)
            else:
                q[i] = value
        return np.array(q, dtype=float)

    @functools.cached_property
    def _q_slots(self) -> tuple[list[float], dict[str, tuple[int, bool]]]:
        """The neutral configuration as a list, and each joint's (q index, continuous?)."""
        return (pin.neutral(self.model).tolist(),
                {name: (info.q_index, info.kind == "continuous")
                 for name, info in self.joints.items()})

    def link_placements(self, values: dict[str, float], links: list[str] | None = None,
                        ) -> dict[str, np.ndarray]:
        """The links' frames (4 x 4, in the model's root frame) with joints at `values`."""
        return self.link_placements_at(self.q(values), links)

    def link_placements_at(self, q: np.ndarray, links: list[str] | None = None,
                           ) -> dict[str, np.ndarray]:
        """`link_placements` at Pinocchio's configuration `q` (see `q`)."""
        model = self.model
        data = self._data
        pin.forwardKinematics(model, data, q)
        out = {}
        for name in (links if links is not None else self.link_frames):
            out[name] = pin.updateFramePlacement(model, data,
                                                 self.link_frames[name]).homogeneous
        return out

    @functools.cached_property
    def _data(self):
        return self.model.createData()

    def parent_joint(self, link: str) -> str | None:
        """The moving joint that carries a link (None: fixed to the root)."""
        jid = int(self.model.frames[self.link_frames[link]].parentJoint)
        return self.model.names[jid] if jid > 0 else None

    def joints_above(self, link: str) -> list[str]:
        """Every moving joint on the way from the root to the link."""
        out = []
        jid = int(self.model.frames[self.link_frames[link]].parentJoint)
        while jid > 0:
            out.append(self.model.names[jid])
            jid = int(self.model.parents[jid])
        return out


def _axis(joint) -> np.ndarray:
    short = joint.shortname()
    letter = short[-1]
    if letter in "XYZ" and not short.endswith("Unaligned"):
        return np.eye(3)["XYZ".index(letter)]
    try:
        return np.asarray(joint.extract().axis, dtype=float)
    except AttributeError:
        return np.zeros(3)


# -- the PR2 ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Mimic:
    """A joint that follows another one: value = multiplier * leader + offset."""

    joint: str
    leader: str
    multiplier: float
    offset: float


class RobotModel(ArticulatedModel):
    """The PR2 from example-robot-data: its meshes, the SRDF's pairs that never collide,
    its joint limits and the mimic joints of its grippers."""

    def __init__(self, urdf: Path, package_dir: Path, srdf: Path | None):
        super().__init__(urdf, [str(package_dir)])
        self.srdf = srdf
        self.mimics = _mimics(urdf)
        self.disabled_pairs = _disabled_pairs(srdf)
        self.base_link = self.model.frames[1].name if len(self.model.frames) > 1 else ""
        self._fixed_together = {link: self.parent_joint(link) for link in self.link_frames}

    def with_mimics(self, values: dict[str, float]) -> dict[str, float]:
        """The values with every mimic joint set from its leader (where the leader is
        given), as the URDF's mimic tags say."""
        out = dict(values)
        for mimic in self.mimics:
            if mimic.leader in values:
                out[mimic.joint] = mimic.multiplier * values[mimic.leader] + mimic.offset
        return out

    def followers(self, leader: str) -> list[str]:
        return [m.joint for m in self.mimics if m.leader == leader]

    @functools.cached_property
    def followers_of_any(self) -> frozenset[str]:
        """Every joint that follows another (a mimic tag)."""
        return frozenset(m.joint for m in self.mimics)

    def may_collide(self, link_a: str, link_b: str) -> bool:
        """Whether two links of the robot are checked against each other: not a pair the
        SRDF disables, nor two links fixed to one another (they never move apart)."""
        return (frozenset((link_a, link_b)) not in self.disabled_pairs
                and self._fixed_together[link_a] != self._fixed_together[link_b])


def _mimics(urdf: Path) -> list[Mimic]:
    root = ET.parse(urdf).getroot()
    out = []
    for joint in root.iter("joint"):
        mimic = joint.find("mimic")
        if mimic is not None and mimic.get("joint"):
            out.append(Mimic(joint.get("name", ""), mimic.get("joint", ""),
                             float(mimic.get("multiplier", "1")),
                             float(mimic.get("offset", "0"))))
    return out


def _disabled_pairs(srdf: Path | None) -> frozenset[frozenset[str]]:
    """The link pairs the SRDF's `disable_collisions` never checks (adjacent links, and
    pairs that cannot meet)."""
    pairs: set[frozenset[str]] = set()
    if srdf is not None and srdf.is_file():
        for element in ET.parse(srdf).getroot().iter("disable_collisions"):
            a, b = element.get("link1"), element.get("link2")
            if a and b:
                pairs.add(frozenset((a, b)))
    return frozenset(pairs)


@functools.cache
def pr2_model() -> RobotModel:
    """The PR2's model, built once per process."""
    share = pr2_share_folder()
    urdf = share / PR2_URDF_SUBPATH
    srdf = share / "pr2_description" / "srdf" / "pr2.srdf"
    # (`package://example-robot-data/robots/...`: the folder above example-robot-data)
    return RobotModel(urdf, share.parent.parent, srdf)


# -- the kitchen and the items ---------------------------------------------------------
@functools.cache
def _kitchen_model(urdf: str, digest: str) -> ArticulatedModel:
    return ArticulatedModel(Path(urdf), [str(Path(urdf).parent)])


def kitchen_model(urdf: Path) -> ArticulatedModel:
    """A world URDF's model (drawers and doors are its joints), once per file content."""
    return _kitchen_model(str(Path(urdf).resolve()), file_digest(urdf))


@dataclass(frozen=True)
class ItemModel:
    """An item's shapes (in the item's frame: the centre of its bottom face) and size."""

    type: str
    shapes: tuple[Shape, ...]
    extents: tuple[float, float, float]  #: x, y, z size of the upright item
    round: bool  #: turning it about z changes nothing (its yaw symmetry is "any")
    lowest_z: float  #: the bottom of its shapes (0 for the shipped items)
    urdf: Path = field(default=Path())
    #: What its item file says (upright, grasps: see `cramlite.world.item_types`).
    kind: ItemType = field(default_factory=ItemType)
    #: Degrees of a turn about +z that leave it the same (0: any; 360: none): its item
    #: file's, else its shape's (an upright cylinder: any; a square box: 90; a box: 180).
    yaw_symmetry_deg: float = 360.0
    #: Its mass (kg): the sum of its URDF links' masses.
    mass_kg: float = 0.0
    #: Its centre of mass in its frame (its links' inertial origins weighted by their
    #: masses; the middle of its bounds if it has no mass): what must be over what it
    #: stands on.
    centre_of_mass: tuple[float, float, float] = (0.0, 0.0, 0.0)


@functools.cache
def _item_model(urdf: str, digest: str, type_: str) -> ItemModel:
    model = ArticulatedModel(Path(urdf), [str(Path(urdf).parent)])
    root = model.model.frames[1].name if len(model.model.frames) > 1 else ""
    shapes = tuple(s for s in model.shapes)
    if not shapes:
        raise ValueError("the item has no collision geometry")
    placements = model.link_placements({})
    corners = []
    for shape in shapes:
        in_root = placements.get(shape.link, np.eye(4)) @ shape.in_link
        if shape.vertices is not None:
            local = shape.vertices
        else:
            local = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                              for sz in (-1, 1)]) * shape.half + shape.centre
        corners.append(local @ in_root[:3, :3].T + in_root[:3, 3])
    pts = np.vstack(corners)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    moved = tuple(_rebased(s, placements.get(s.link, np.eye(4)), root) for s in shapes)
    kind = item_type(Path(urdf))
    symmetry = kind.yaw_symmetry_deg
    if symmetry is None:
        symmetry = _shape_symmetry(moved)
    mass = float(sum(inertia.mass for inertia in model.model.inertias))
    return ItemModel(type_, moved, tuple(float(v) for v in hi - lo), symmetry == 0.0,
                     float(lo[2]), Path(urdf), kind, symmetry, mass,
                     _centre_of_mass(model, (lo + hi) / 2))


def _centre_of_mass(model: ArticulatedModel, middle: np.ndarray) -> tuple[float, float, float]:
    """The centre of mass of a model's links (in its root frame, its joints at zero: as
    its shapes are placed); `middle` if it has no mass."""
    pm = model.model
    data = pm.createData()
    pin.forwardKinematics(pm, data, pin.neutral(pm))
    total = sum(inertia.mass for inertia in pm.inertias)
    if not total > 0:
        return tuple(float(v) for v in middle)
    moment = sum(inertia.mass * data.oMi[j].act(inertia.lever)
                 for j, inertia in enumerate(pm.inertias))
    return tuple(float(v) for v in moment / total)


def _shape_symmetry(shapes: tuple[Shape, ...]) -> float:
    """The yaw symmetry (degrees) of an item's shapes: 0 for an upright cylinder on its
    axis, 90 / 180 for a box with a square / oblong footprint centred on it, else 360."""
    if len(shapes) != 1:
        return 360.0
    shape = shapes[0]
    upright = abs(shape.in_link[2, 2] - 1.0) < 1e-9
    centred = np.allclose(shape.in_link[:2, 3], 0.0, atol=1e-9)
    if not (upright and centred):
        return 360.0
    if shape.kind == CYLINDER:
        return 0.0
    if shape.kind == BOX:
        return 90.0 if abs(shape.half[0] - shape.half[1]) < 1e-9 else 180.0
    return 360.0


def _rebased(shape: Shape, link_in_root: np.ndarray, root: str) -> Shape:
    """The shape placed in the item's root frame (an item may have several links)."""
    return Shape(shape.name, root, shape.kind, shape.geometry, link_in_root @ shape.in_link,
                 shape.half, shape.centre, shape.radius, shape.vertices, shape.triangles)


def item_model(urdf: Path, type_: str) -> ItemModel:
    """An item URDF's model (with its item file), once per content of both."""
    sidecar = item_type_file(urdf)
    digest = file_digest(urdf) + (file_digest(sidecar) if sidecar.is_file() else "")
    return _item_model(str(Path(urdf).resolve()), digest, type_)
