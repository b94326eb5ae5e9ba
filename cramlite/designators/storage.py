"""Opening and closing drawers and cupboards: `OpenAction`, `CloseAction` (PyCRAM's names).

`AccessingLocation` offers base poses from which an arm can grasp a container's handle and
follow it through the whole opening (or closing): the handle's path is sampled (about a
centimetre apart: straight for a drawer, an arc for a door), each sample solved by IK from
the previous one, and every state of the arm on that path checked with the drawer or door
where it will be then, together with the pre-grasp and the retreat. The base pose must be
free at every stage of the opening (an open drawer or door takes room). The action then
navigates there, grasps the handle, and executes one trajectory in which the arm follows
the handle and the joint moves with it (items inside a drawer ride along), timed at the
handle speed of `ExecutionOptions`. Failures are typed (`ContainerManipulationFailed`) and
fall through to the next base pose or arm.
"""

from __future__ import annotations

import contextlib
import functools
import math
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.designators.actions import NavigateAction, ParkArmsAction
from cramlite.designators.context import RobotContext, _joint_state, occupancy_map
from cramlite.designators.failures import (
    ContainerManipulationFailed,
    ObjectNotFound,
    PlanFailure,
)
from cramlite.designators.grasps import Grasp, in_base_frame
from cramlite.designators.locations import CostmapLocation, reaching_seed
from cramlite.designators.motions import MoveArmJointsMotion, MoveGripperMotion, gripper_joints
from cramlite.designators.tasks import ActionDesignator, recorded
from cramlite.motion.footprint import OccupancyMap
from cramlite.motion.ik import ARMS, ArmIK, IKOptions, arm_ik, arm_joint_names
from cramlite.motion.trajectory import time_along_path, wrap_angle
from cramlite.process_cache import ProcessCache
from cramlite.scene.gripper import gripper_geometry
from cramlite.scene.transforms import Vec3
from cramlite.world.containers import Container
from cramlite.world.pr2 import PARK_JOINTS, TORSO_JOINT

BasePose = tuple[float, float, float]
#: Handle path samples: about this far apart along the handle's way.
HANDLE_STEP_M = 0.02
#: A handle's grasp (only its name is used: base poses around the handle are ranked as
#: for any grasp).
HANDLE = Grasp("handle", 0.0, 0.0, None)
#: Pre-grasp and retreat: this far back from the handle along the approach.
HANDLE_CLEARANCE_M = 0.10
#: Base poses may face the handle up to this far off the container's front normal.
MAX_SQUINT_RAD = math.radians(60)
#: Stages of the opening at which the base pose must be clear of the drawer or door.
FOOTPRINT_STAGES = 5
#: Handle IK chains kept for the process, at most 20 000 (a pure function of the handle's
#: poses, the base pose, the arm and the torso; thousands of solves for a cupboard's door).
_HANDLE_IK: ProcessCache[tuple[list[float], list[dict[str, float]], dict, dict] | None] = \
    ProcessCache(20_000)
#: How closely the hand follows the handle: IK on the handle's path is solved to this
#: (the arm's IK stops at 1 mm, and the fingers closed on a 2 cm bar may be at most 2 mm
#: inside it: a hand 1.7 mm off the bar, between two samples, put a fingertip 2.3 mm in)...
HANDLE_IK_OPTIONS = IKOptions(position_tolerance_m=2e-4, rotation_tolerance_rad=2e-3)
#: ...and the arm's straight joint-space way between two samples stays this close to the
#: handle's own way (checked at a quarter, half and three quarters of it); where it does
#: not, a sample is solved half way, at most `HANDLE_REFINEMENTS` times over.
HANDLE_TRACKING_M = 5e-4
HANDLE_REFINEMENTS = 4


@dataclass(frozen=True)
class HandlePath:
    """The joint values of the container along an opening or closing, the handle grasp
    pose (world) at each, and the distance the handle has travelled (m)."""

    values: np.ndarray
    poses: list[pin.SE3]
    arc_m: np.ndarray

    @functools.cached_property
    def key(self) -> tuple:
        """The poses, rounded: what the IK along the handle depends on (a dictionary key)."""
        return tuple(tuple(np.round(pose.homogeneous[:3].ravel(), 5)) for pose in self.poses)


def handle_path(ctx: RobotContext, container: Container, start: float, end: float,
                ) -> HandlePath:
    """The handle's way from `start` to `end` (kept per world, by where every drawer and
    door stands: a stretch is asked for at every attempt to open or close it)."""
    key = ("handle path", container.name, start, end,
           *ctx.scene.world_joint_positions().values())
    if key not in ctx.scene.cache:
        ctx.scene.cache[key] = _handle_path(ctx.scene, container, start, end)
    return ctx.scene.cache[key]


def _handle_path(scene, container: Container, start: float, end: float) -> HandlePath:
    with scene.world_joint_at(container.joint, end):
        far = _grasp_pose(scene, container)
    with scene.world_joint_at(container.joint, start):
        near = _grasp_pose(scene, container)
    length = float(np.linalg.norm(far.translation - near.translation))
    if container.kind != "drawer":  # an arc: its length from the angle and the radius
        with scene.world_joint_at(container.joint, 0.0):
            hinge = np.asarray(scene.link_frame(container.link)[0])
        radius = float(np.linalg.norm((near.translation - hinge)[:2]))
        length = radius * abs(end - start)
    count = max(2, math.ceil(length / HANDLE_STEP_M) + 1)
    values = np.linspace(start, end, count)
    poses = []
    for value in values:
        with scene.world_joint_at(container.joint, float(value)):
            poses.append(_grasp_pose(scene, container))
    steps = [float(np.linalg.norm(b.translation - a.translation))
             for a, b in zip(poses[:-1], poses[1:], strict=True)]
    return HandlePath(values, poses, np.concatenate([[0.0], np.cumsum(steps)]))


def _grasp_pose(scene, container: Container) -> pin.SE3:
    """Where the tool frame grasps the handle: at the grasp point, pointing into the
    container's front (the moving link's x axis), rolled to the handle's bar."""
    pos, (qx, qy, qz, qw) = scene.link_frame(container.link)
    frame = pin.SE3(pin.Quaternion(qw, qx, qy, qz).toRotationMatrix(), np.asarray(pos))
    roll = pin.SE3(pin.rpy.rpyToMatrix(container.roll, 0.0, 0.0), np.asarray(container.grasp))
    return frame * roll


def handle_width(scene, container: Container) -> float:
    """How wide a container's handle is between the fingers at the grasp: the extent,
    along the direction the fingers close, of the handle's box that holds the grasp
    point (the kitchen's handles are 2 cm bars)."""
    key = ("handle width", container.name)
    if key not in scene.cache:
        closing = pin.rpy.rpyToMatrix(container.roll, 0.0, 0.0)[:, 1]  # tool y, link frame
        point = np.asarray(container.grasp, dtype=float)
        width = None
        for shape in scene.kitchen.shapes_by_link.get(container.handle, []):
            # (the handle link is fixed to the container's link, frames alike)
            local = np.linalg.inv(shape.in_link)
            inside = local[:3, :3] @ point + local[:3, 3] - shape.centre
            if np.all(np.abs(inside) <= shape.half + 1e-6):
                axis = shape.in_link[:3, :3].T @ closing
                width = 2 * float(np.abs(axis) @ shape.half)
                break
        if width is None:
            raise ValueError(f"{container.name}: no handle shape holds its grasp point")
        scene.cache[key] = width
    return scene.cache[key]


def backed_off(pose: pin.SE3, distance: float) -> pin.SE3:
    return pin.SE3(pose.rotation, pose.translation - distance * pose.rotation[:, 0])


@dataclass(frozen=True)
class AccessPose:
    """A base pose and arm that can follow a handle, with every joint state checked."""

    base: BasePose
    arm: str
    container: str
    names: tuple[str, ...]  #: torso and the arm's joints (the order of `states`)
    pre_joints: dict[str, float]
    states: np.ndarray  #: arm states along the handle path (grasp first)
    values: np.ndarray  #: the container's joint value at each state
    arc_m: np.ndarray  #: the handle's travel at each state
    post_joints: dict[str, float]

    def joints_at(self, i: int) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.states[i], strict=True)}

    def describe(self) -> str:
        x, y, yaw = self.base
        return f"base ({x:.2f}, {y:.2f}, {math.degrees(yaw):.0f} deg) {self.arm} arm"


class AccessingLocation:
    """Base poses from which one of `arms` follows `container`'s handle from joint value
    `start` to `end`, best first (stand-off and travel, as `CostmapLocation`)."""

    def __init__(self, container: Container, start: float, end: float,
                 arms: Sequence[str] = ARMS, max_ik_checks: int = 24):
        self.container = container
        self.start, self.end = start, end
        self.arms = list(arms)
        self.max_ik_checks = max_ik_checks
        self.rejected = {"footprint": 0, "ik": 0, "arm collision": 0, "park": 0}

    def ground(self, ctx: RobotContext) -> Iterator[AccessPose]:
        path = handle_path(ctx, self.container, self.start, self.end)
        middle = path.poses[len(path.poses) // 2]
        facing = math.atan2(middle.rotation[1, 0], middle.rotation[0, 0])
        point = tuple(middle.translation)
        maps = self._stage_maps(ctx)
        rings = CostmapLocation(point, [HANDLE], "", self.arms)
        checks = 0
        for _, base, arm, _ in rings.candidates(ctx):
            if abs(wrap_angle(base[2] - facing)) > MAX_SQUINT_RAD:
                continue
            if not all(_footprint_free(ctx, swept, base) for swept in maps):
                self.rejected["footprint"] += 1
                continue
            if checks >= self.max_ik_checks:
                return
            checks += 1
            access = self.reach_from(ctx, base, arm, path)
            if access is not None:
                yield access

    def _stage_maps(self, ctx: RobotContext) -> list:
        """The kitchen's maps with the container at FOOTPRINT_STAGES places along the
        stretch, as one map blocked wherever one of them is (where they can be joined:
        one footprint check a base pose instead of one a stage, the same answers)."""
        key = ("swept map", self.container.joint, round(self.start, 4), round(self.end, 4),
               _joint_state(ctx.scene))  # (by what the maps themselves are kept by)
        if key not in ctx.scene.cache:
            out = []
            for value in np.linspace(self.start, self.end, FOOTPRINT_STAGES):
                with ctx.scene.world_joint_at(self.container.joint, float(value)):
                    out.append(occupancy_map(ctx.scene))
            joined = OccupancyMap.union(out)
            ctx.scene.cache[key] = out if joined is None else [joined]
        return ctx.scene.cache[key]

    def reach_from(self, ctx: RobotContext, base: BasePose, arm: str,
                   path: HandlePath | None = None) -> AccessPose | None:
        """IK along the handle path from one base pose, every state checked (or None)."""
        path = path or handle_path(ctx, self.container, self.start, self.end)
        names = tuple([TORSO_JOINT, *arm_joint_names(arm)])
        torso = ctx.scene.joint_positions([TORSO_JOINT])[TORSO_JOINT]
        solved = self._solve(ctx, base, arm, torso, path)
        if solved is None:
            self.rejected["ik"] += 1
            return None
        at, chain, pre, post = solved
        states, values, arc = _densify(ctx, names, at, chain, path)
        if not self._free(ctx, base, arm, names, states, values, pre, post):
            self.rejected["arm collision"] += 1
            return None
        if not self._parks_after(ctx, base, arm, names, post):
            self.rejected["park"] += 1
            return None
        return AccessPose(base, arm, self.container.name, names, pre, states, values, arc,
                          post)

    def _solve(self, ctx: RobotContext, base: BasePose, arm: str, torso: float,
               path: HandlePath,
               ) -> tuple[list[float], list[dict[str, float]], dict, dict] | None:
        """IK along the handle path (each sample from the previous one), and for the
        pre-grasp and the retreat: a pure function of the container, the stretch, the base
        pose, the arm and the torso (its starts are drawn from a generator seeded by them),
        so it is computed once per world and reused; what the world around looks like is
        checked every time (`_free`)."""
        key = ("handle ik", self.container.name, round(self.start, 4), round(self.end, 4),
               tuple(round(v, 4) for v in base), arm, round(torso, 4))
        cache = ctx.scene.cache
        if key not in cache:
            # (also kept for the process, by the handle's poses themselves: another world
            # of the same kitchen, e.g. the next setup a bench worker loads, reuses it)
            cache[key] = _HANDLE_IK.get_or_compute((key, path.key), lambda: _handle_ik(
                arm, base, torso, path, np.random.default_rng([zlib.crc32(repr(key).encode())])))
        return cache[key]


    def _free(self, ctx: RobotContext, base: BasePose, arm: str, names: tuple[str, ...],
              states: np.ndarray, values: np.ndarray, pre: dict[str, float],
              post: dict[str, float]) -> bool:
        """Every state free with the container (and what is inside) where it is then: the
        gripper open at the pre-grasp and retreat, closed on the handle (which it may
        touch) in between."""
        container = self.container
        closed = gripper_geometry().closing_angle(handle_width(ctx.scene, container))
        checks = {gripper: ctx.collisions.check(names, ignore=(container.handle,), base=base,
                                                fixed=gripper_joints(arm, gripper, closed))
                  for gripper in ("open", "close")}
        opened = checks["open"]
        opened.move_world_joint(container.joint, self.start)  # (items inside ride along)
        if not opened.is_free(np.array([pre[n] for n in names])):
            return False
        # (the states along the handle as one batch, each with the container where it is)
        if not checks["close"].states_free_as_joint_moves(container.joint, values, states):
            return False
        opened.move_world_joint(container.joint, self.end)
        return opened.is_free(np.array([post[n] for n in names]))

    def _parks_after(self, ctx: RobotContext, base: BasePose, arm: str,
                     names: tuple[str, ...], post: dict[str, float]) -> bool:
        """Can the arm be parked there afterwards (its park pose free, the gripper open,
        the container where the stretch ends)? A door opened part of the way stood where
        the parked left hand's fingers were, and every action after it, parking first,
        failed."""
        check = ctx.collisions.check(names, ignore=(self.container.handle,), base=base,
                                     fixed=gripper_joints(arm, "open"))
        check.move_world_joint(self.container.joint, self.end)
        parked = {**post, **PARK_JOINTS[arm]}
        return check.is_free(np.array([parked[n] for n in names]))

    def describe_rejections(self) -> str:
        total = sum(self.rejected.values())
        if not total:
            return ""
        why = {"footprint": "base in the way of the opening", "ik": "handle out of reach",
               "arm collision": "arm would hit something",
               "park": "arm could not park there afterwards"}
        return (f"{total} base poses ({'/'.join(self.arms)} arm): " +
                ", ".join(f"{n} {why[k]}" for k, n in self.rejected.items() if n))


@functools.cache
def handle_ik(arm: str) -> ArmIK:
    """The arm's IK solver for following a handle (`HANDLE_IK_OPTIONS`), once a process."""
    return ArmIK(arm, options=HANDLE_IK_OPTIONS)


def _handle_ik(arm: str, base: BasePose, torso: float, path: HandlePath,
               rng: np.random.Generator,
               ) -> tuple[list[float], list[dict[str, float]], dict, dict] | None:
    """The arm's states along the handle path, from the first start (reaching forward,
    tucked, random) whose solution can be followed all the way: where on the path each
    is (an index into its poses, fractional for the samples added in between, see
    `_followed_closely`), the states, the pre-grasp and the retreat."""
    ik, close = arm_ik(arm), handle_ik(arm)
    ends = [in_base_frame(path.poses[0], base), in_base_frame(path.poses[-1], base)]
    clear = [in_base_frame(backed_off(path.poses[0], HANDLE_CLEARANCE_M), base),
             in_base_frame(backed_off(path.poses[-1], HANDLE_CLEARANCE_M), base)]
    # both ends first: most base poses fail there, before the whole path is solved
    if any(ik.solve(end, rng, reaching_seed(arm), fixed_torso_m=torso, restarts=4,
                    near_limits_ok=True) is None for end in ends):
        return None
    poses = [in_base_frame(pose, base) for pose in path.poses]
    for start in (reaching_seed(arm), {**PARK_JOINTS[arm], TORSO_JOINT: torso}, None):
        first = close.solve(ends[0], rng, start, fixed_torso_m=torso,
                            restarts=0 if start else 2)
        if first is None:
            continue
        # the pre-grasp before the path: from here it fails more often than the path does
        pre = ik.solve(clear[0], rng, first.joints, fixed_torso_m=torso, restarts=1)
        if pre is None:
            continue
        chain = [first.joints]
        for pose in poses[1:]:
            solution = close.solve(pose, rng, chain[-1], fixed_torso_m=torso, restarts=0)
            if solution is None:
                break
            chain.append(solution.joints)
        else:
            post = ik.solve(clear[1], rng, chain[-1], fixed_torso_m=torso, restarts=1)
            if post is None:
                continue
            followed = _followed_closely(close, torso, poses, chain, rng)
            if followed is not None:
                return (*followed, pre.joints, post.joints)
    return None


def _followed_closely(ik: ArmIK, torso: float, poses: list[pin.SE3],
                      chain: list[dict[str, float]], rng: np.random.Generator,
                      ) -> tuple[list[float], list[dict[str, float]]] | None:
    """The chain (one state per pose of the handle's path, `poses`: in the base's frame)
    with states added between two where
    the arm's straight joint-space way between them strays from the handle's way by more
    than `HANDLE_TRACKING_M`: solved half way along the handle (its pose in between by
    the screw motion from one to the other, exact for a door's arc and a drawer's line),
    from the joints half way. Returns where on the path each state is (fractional
    indices) and the states; None if the hand still strays after `HANDLE_REFINEMENTS`
    halvings (this base pose cannot follow the handle closely enough). (A solve from
    given joints draws no random number.)"""

    def strays(a: dict[str, float], b: dict[str, float], pa: pin.SE3, pb: pin.SE3,
               ) -> bool:
        for f in (0.25, 0.5, 0.75):
            joints = ik.between(a, b, f)
            target = pin.SE3.Interpolate(pa, pb, f)
            if np.linalg.norm(ik.forward(joints).translation - target.translation) > \
                    HANDLE_TRACKING_M:
                return True
        return False

    def fill(ia: float, a: dict, pa: pin.SE3, ib: float, b: dict, pb: pin.SE3,
             depth: int) -> list[tuple[float, dict]] | None:
        if not strays(a, b, pa, pb):
            return []
        if depth == 0:
            return None
        middle = pin.SE3.Interpolate(pa, pb, 0.5)
        solution = ik.solve(middle, rng, ik.between(a, b, 0.5), fixed_torso_m=torso,
                            restarts=0)
        if solution is None:
            return None
        im = (ia + ib) / 2
        before = fill(ia, a, pa, im, solution.joints, middle, depth - 1)
        after = fill(im, solution.joints, middle, ib, b, pb, depth - 1)
        if before is None or after is None:
            return None
        return [*before, (im, solution.joints), *after]

    at, out = [0.0], [chain[0]]
    for i in range(1, len(chain)):
        added = fill(i - 1, chain[i - 1], poses[i - 1], i, chain[i], poses[i],
                     HANDLE_REFINEMENTS)
        if added is None:
            return None
        for position, joints in added:
            at.append(position)
            out.append(joints)
        at.append(float(i))
        out.append(chain[i])
    return at, out


def _footprint_free(ctx: RobotContext, occupancy, base: BasePose) -> bool:
    checker = ctx.base_checker()
    saved = checker.occupancy
    checker.occupancy = occupancy
    try:
        return checker.is_free(*base)
    finally:
        checker.occupancy = saved


def _densify(ctx: RobotContext, names: tuple[str, ...], at: list[float],
             chain: list[dict[str, float]], path: HandlePath,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The IK chain (each state at its place `at` on the path: a fractional index into
    its poses) with states inserted where a joint would jump more than the allowed step
    (the container's value and the handle's travel interpolated with them)."""
    limits = ctx.limits
    steps = limits.max_steps(names)
    index = np.arange(len(path.values))
    states = [np.array([chain[0][n] for n in names])]
    places = [at[0]]
    for i in range(1, len(chain)):
        a = states[-1]
        b = limits.unwrap_goal(names, a, np.array([chain[i][n] for n in names]))
        count = max(1, math.ceil(float(np.max(np.abs(b - a) / steps)) - 1e-9))
        for k in range(1, count + 1):
            f = k / count
            states.append(a + f * (b - a))
            places.append(at[i - 1] + f * (at[i] - at[i - 1]))
    return (np.array(states), np.interp(places, index, path.values),
            np.interp(places, index, path.arc_m))


@dataclass(frozen=True)
class FollowHandleMotion:
    """The arm follows the handle along a checked path; the drawer or door moves with it."""

    access: AccessPose
    joint: str

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        a = self.access
        trajectory = time_along_path(a.names, a.states, a.arc_m, ctx.limits,
                                     ctx.options.handle_speed_m_s,
                                     ctx.options.handle_accel_m_s2,
                                     world={self.joint: a.values})
        ctx.move_joints(trajectory)


def container_named(ctx: RobotContext, name: str) -> Container:
    container = ctx.scene.containers.get(name)
    if container is None:
        raise ObjectNotFound(f"no container {name!r} in the world; expected one of "
                             f"{', '.join(ctx.scene.containers) or 'none'}", obj=name)
    return container


def _move_container(ctx: RobotContext, name: str, target: str, arms: Sequence[str] | None,
                    ) -> None:
    container = container_named(ctx, name)
    goal = container.open_value if target == "open" else 0.0
    now = ctx.scene.world_joint_positions()[container.joint]
    if abs(now - goal) < 1e-3:
        return
    free = [a for a in (arms or ARMS) if a not in ctx.holding]
    if not free:
        raise ContainerManipulationFailed(f"cannot {target} it: both hands are full", obj=name)
    from cramlite.designators.container_sweep import sweep_problem

    problem = sweep_problem(ctx, container, now, goal)
    if problem:  # (before the robot moves: the drawer or door itself would push into it)
        raise ContainerManipulationFailed(f"cannot {target} it: {problem}", obj=name)
    tried: list[str] = []
    # the whole way from one base pose, or else in stages (a door that opens wide: pulled
    # half way from one pose, then on from another), each from its own base pose
    for stages in (1, 2, 3):
        values = np.linspace(now, goal, stages + 1)
        done = 0
        for start, end in zip(values[:-1], values[1:], strict=True):
            if not _move_stage(ctx, container, float(start), float(end), free, tried,
                               whole=stages == 1):
                break
            done += 1
        if done == stages:
            if target == "open" and name not in ctx.opened:
                ctx.opened.append(name)
            elif target == "close" and name in ctx.opened:
                ctx.opened.remove(name)
            return
        if done:  # part of the way: the rest cannot be done in smaller steps from here
            break
    raise ContainerManipulationFailed(f"no base pose and arm can {target} it", obj=name,
                                      tried=tried)


def _move_stage(ctx: RobotContext, container: Container, start: float, end: float,
                arms: list[str], tried: list[str], whole: bool = False) -> bool:
    """Follow the handle from `start` to `end` from the first base pose and arm that can;
    False (and what was tried) if none can. `whole`: the whole way in one go."""
    # a whole swing for which no base pose checked could follow the handle (opening, say)
    # is not searched again the other way in the same trial with the same or fewer arms:
    # it is done in stages straight away (at worst in one stage more than needed; a stage
    # is never skipped, so no opening or closing that can be done is given up)
    stretch = (container.name, round(min(start, end), 4), round(max(start, end), 4))
    if whole and any(key[:3] == stretch and set(arms) <= key[3]
                     for key in ctx.unfollowable):
        tried.append(f"{start:.2f} to {end:.2f}: no base pose could follow it before")
        return False
    location = AccessingLocation(container, start, end, arms)
    verb = "opened" if end > start else "closed"
    offered = False
    for attempt, access in enumerate(location.ground(ctx)):
        offered = True
        if attempt >= ctx.options.max_candidates:
            break
        try:
            _follow(ctx, container, access)
            ctx.note(f"{verb} {container.name} from {start:.2f} to {end:.2f} from "
                     f"{access.describe()}")
            return True
        except PlanFailure as failure:
            tried.append(f"{access.describe()}: {failure.kind}: {failure.reason}")
            ParkArmsAction().perform(ctx)
    if whole and not offered:
        ctx.unfollowable.add((*stretch, frozenset(arms)))
    rejected = location.describe_rejections()
    if rejected:
        tried.append(f"{start:.2f} to {end:.2f}: {rejected}")
    return False


def _follow(ctx: RobotContext, container: Container, access: AccessPose) -> None:
    touch = (container.handle,)
    NavigateAction(access.base).perform(ctx)
    MoveGripperMotion(access.arm, "open", touch).perform(ctx)
    MoveArmJointsMotion(access.pre_joints, touch).perform(ctx)
    try:
        MoveArmJointsMotion(access.joints_at(0), touch).perform(ctx)
        MoveGripperMotion(access.arm, "close", touch,
                          width_m=handle_width(ctx.scene, container)).perform(ctx)
        FollowHandleMotion(access, container.joint).perform(ctx)
    except PlanFailure:
        _let_go(ctx, container, access)
        raise
    MoveGripperMotion(access.arm, "open", touch).perform(ctx)
    MoveArmJointsMotion(access.post_joints, touch).perform(ctx)
    ParkArmsAction(access.arm).perform(ctx)


def _let_go(ctx: RobotContext, container: Container, access: AccessPose) -> None:
    """After a failure at the handle: open the gripper and back off the handle (to the
    pre-grasp, or the retreat if the container got to the end), so the arm can be parked
    (from around the handle no path that may not touch it is free). A handle stopped part
    of the way (a real robot's failure: simulated motions run whole or not at all) may
    leave no free way back to the pre-grasp; then the arm stays, as before."""
    touch = (container.handle,)
    value = ctx.scene.world_joint_positions()[container.joint]
    back = access.post_joints if abs(value - access.values[-1]) < 1e-3 else access.pre_joints
    with contextlib.suppress(PlanFailure):
        MoveGripperMotion(access.arm, "open", touch).perform(ctx)
        MoveArmJointsMotion(back, touch).perform(ctx)


@dataclass
class OpenAction(ActionDesignator):
    """Open a drawer or a cupboard door: grasp its handle and pull it open. Returns the
    container's joint position where it ended (m for a drawer, rad for a door)."""

    container: str  #: the container's name (see the world's containers)
    arms: Sequence[str] | None = None  #: arms to try (default: the free ones)

    def execute(self, ctx: RobotContext) -> float:
        _move_container(ctx, self.container, "open", self.arms)
        return ctx.scene.world_joint_positions()[_container(ctx, self.container).joint]

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        if not ctx.scene.is_open(_container(ctx, self.container)):
            raise ContainerManipulationFailed("not open after opening it", obj=self.container)


@dataclass
class CloseAction(ActionDesignator):
    """Close a drawer or a cupboard door: grasp its handle and push it shut. Returns the
    container's joint position where it ended (m for a drawer, rad for a door)."""

    container: str  #: the container's name
    arms: Sequence[str] | None = None  #: arms to try (default: the free ones)

    def execute(self, ctx: RobotContext) -> float:
        _move_container(ctx, self.container, "close", self.arms)
        return ctx.scene.world_joint_positions()[_container(ctx, self.container).joint]

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        container = _container(ctx, self.container)
        if abs(ctx.scene.world_joint_positions()[container.joint]) > 1e-3:
            raise ContainerManipulationFailed("not closed after closing it",
                                              obj=self.container)


def _container(ctx: RobotContext, name: str) -> Container:
    if name not in ctx.scene.containers:
        raise ContainerManipulationFailed(f"no container {name!r}; expected one of "
                                          f"{', '.join(ctx.scene.containers)}", obj=name)
    return ctx.scene.containers[name]


def container_of(ctx: RobotContext, obj: str) -> Container | None:
    """The container an item is inside now, if any (not if it is held)."""
    return ctx.scene.container_of(obj)


def container_at(ctx: RobotContext, point: Vec3,
                 ) -> tuple[Container, Vec3] | tuple[None, None]:
    """The container whose inside holds a point given as it is with the container closed
    (a place pose in a drawer), and the point in the inside's frame; (None, None) if none."""
    return ctx.scene.container_at(point)


@contextlib.contextmanager
def virtually_open(ctx: RobotContext, container: Container) -> Iterator[None]:
    """Plan as if the container were open (the scene's belief and the base planner's
    map), without opening it."""
    with ctx.scene.world_joint_at(container.joint, container.open_value):
        saved = ctx.checker.occupancy
        ctx.checker.occupancy = occupancy_map(ctx.scene)
        ctx.footprint_stale = True  # what sticks out, against the open container too
        try:
            yield
        finally:
            ctx.checker.occupancy = saved
            ctx.footprint_stale = True


def is_open(ctx: RobotContext, container: Container) -> bool:
    return ctx.scene.is_open(container)
