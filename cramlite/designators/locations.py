"""Location designators: many candidates, best first, each checked before it is offered.

`CostmapLocation`: base poses from which an arm reaches a point with a grasp, to pick an
object up there or to put a held one down. Candidates lie on rings around the point,
facing it, with the arm's shoulder in line; they are scored by stand-off (close to the
arm's sweet spot) and by how far the robot would have to drive, then checked in that
order: footprint free in the 2D map, then for every configuration the actions will use
(picking: pre-grasp, grasp, lift, park; placing: pre-place above the spot, place,
retreat, park) an IK solution and no robot link or carried object inside the kitchen or
another item (or the robot itself), asked of the planning scene. Only fully checked
candidates are offered.

`PlacingLocation`: where an object may be put: at a target (then small offsets within
the placing tolerance), or on free spots of a surface, nearest to a preferred point.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from cramlite.designators.context import RobotContext
from cramlite.designators.grasps import (
    CARRY_BOTTOM_Z_M,
    CARRY_LOWER_BOTTOMS_M,
    LIFT_M,
    PREGRASP_OFFSET_M,
    PREGRASP_RISE_M,
    RETREAT_RISE_M,
    Grasp,
    backed_off,
    carry_pose,
    in_base_frame,
    raised,
    relative_pose,
    tool_for_item,
    tool_pose,
)
from cramlite.designators.motions import gripper_joints
from cramlite.designators.objects import ObjectDesignator
from cramlite.motion.ik import ARMS, arm_ik, arm_joint_names
from cramlite.motion.trajectory import densify
from cramlite.process_cache import ProcessCache
from cramlite.scene.collision import HeldObject
from cramlite.scene.robot_points import upper_body_parts, upper_body_points
from cramlite.scene.transforms import Quat, Vec3, pose_matrix, quat_yaw
from cramlite.world.pr2 import PARK_JOINTS, TORSO_JOINT, TORSO_UP_M

BasePose = tuple[float, float, float]
SHOULDER_OFFSET_M = 0.188  # lateral offset of each shoulder from the base centre
STANDOFFS_M = tuple(round(0.45 + 0.025 * i, 3) for i in range(15))  # 0.45 .. 0.80
IDEAL_STANDOFF_M = 0.60
TRAVEL_WEIGHT = 0.25
PICK, PLACE = "pick", "place"
#: Where an item is put when its target is asked for: the target, else (taken, or out of
#: reach) 8 spots on each of these circles around it.
TARGET_RINGS_M = (0.015, 0.03)
#: Grasp solutions tried per base pose when the approach or departure has none near it.
IK_ATTEMPTS = 3
#: Random restarts of a grasp's IK: a base pose that needs more is left for the next one.
GRASP_IK_RESTARTS = 4
Relative = tuple[Vec3, Quat]


@dataclass(frozen=True)
class ReachablePose:
    """A base pose with the arm, grasp and checked joint angles that reach the point.

    Picking: `pre_joints` pre-grasp, `joints` grasp, `post_joints` lift (holding it).
    Placing: `pre_joints` above the spot, `joints` place, `post_joints` retreat (empty).
    `relative` is the object's pose in the tool frame, as grasped / as it will be held.
    """

    base: BasePose
    arm: str
    grasp: Grasp
    joints: dict[str, float]
    pre_joints: dict[str, float]
    post_joints: dict[str, float]
    relative: Relative
    #: Every motion between these configurations is a free straight joint-space path.
    straight: bool = True
    #: The tool's yaw at the grasp (or place) and, placing, the item's yaw it gives.
    tool_yaw: float = 0.0
    item_yaw: float = 0.0
    #: The tool frame at the grasp (or place): position in the world.
    tool_position: Vec3 = (0.0, 0.0, 0.0)

    def describe(self) -> str:
        x, y, yaw = self.base
        return f"base ({x:.2f}, {y:.2f}, {math.degrees(yaw):.0f} deg) {self.arm} arm {self.grasp}"


REJECTIONS = {"footprint": "base inside fixed geometry", "ik": "out of the arm's reach (IK)",
              "arm collision": "arm or object would hit something",
              "grasp yaw": "the grasp's tool yaw too far off the robot's heading"}


class CostmapLocation:
    """Base poses from which one of `arms` reaches `point` (an object's bottom centre)
    with one of `grasps` (in order of preference), to pick `obj` up there (standing as
    `orientation`) or (`purpose=PLACE`) to put it down there, held as `relative` (its pose
    in the tool frame), turned to `target_yaw` or a turn of it by `symmetry_deg` (None:
    any yaw)."""

    def __init__(self, point: Vec3, grasps: Sequence[Grasp], obj: str,
                 arms: Sequence[str] = ARMS, purpose: str = PICK,
                 orientation: Quat = (0.0, 0.0, 0.0, 1.0), relative: Relative | None = None,
                 angle_step_deg: float = 10.0, max_ik_checks: int = 24,
                 max_ik_checks_if_none: int = 48, target_yaw: float | None = None,
                 symmetry_deg: float = 360.0):
        if purpose not in (PICK, PLACE):
            raise ValueError(f"purpose must be {PICK!r} or {PLACE!r}")
        if purpose == PLACE and relative is None:
            raise ValueError("placing needs the object's pose in the tool frame (relative)")
        self.point = point
        self.obj = obj
        self.arms = list(arms)
        self.grasps = list(grasps)
        self.target_yaw = target_yaw
        self.symmetry_deg = symmetry_deg
        self.purpose = purpose
        self.orientation = orientation
        self.relative = relative
        self.angle_step_deg = angle_step_deg
        #: Candidates checked (IK and the arm's motions) before giving up, and how far to
        #: go on while none has passed (near an open door most of the closest fail).
        self.max_ik_checks = max_ik_checks
        self.max_ik_checks_if_none = max(max_ik_checks, max_ik_checks_if_none)
        self.rejected: dict[str, int] = dict.fromkeys(REJECTIONS, 0)

    def candidates(self, ctx: RobotContext) -> Iterator[tuple[float, BasePose, str, Grasp]]:
        """(score, base pose, arm, grasp), best (lowest) score first."""
        here = ctx.scene.base
        px, py, _ = self.point
        steps = round(360 / self.angle_step_deg)
        yaw = np.radians(np.arange(steps) * self.angle_step_deg) - math.pi
        standoff = np.array(STANDOFFS_M)[:, None]
        ux, uy = np.cos(yaw)[None, :], np.sin(yaw)[None, :]
        scores, poses, labels = [], [], []
        for arm in self.arms:
            side = 1.0 if arm == "right" else -1.0
            x = px - standoff * ux - side * SHOULDER_OFFSET_M * uy
            y = py - standoff * uy + side * SHOULDER_OFFSET_M * ux
            score = (np.abs(standoff - IDEAL_STANDOFF_M)
                     + TRAVEL_WEIGHT * np.hypot(x - here[0], y - here[1]))
            pose = np.stack([x, y, np.broadcast_to(yaw, x.shape)], axis=-1).reshape(-1, 3)
            for rank, grasp in enumerate(self.grasps):
                scores.append(score.ravel() + 0.05 * rank)
                poses.append(pose)
                labels += [(arm, grasp)] * len(pose)
        score_all = np.concatenate(scores)
        pose_all = np.concatenate(poses)
        for i in np.argsort(score_all, kind="stable"):
            x, y, yaw_i = pose_all[i]
            yield float(score_all[i]), (float(x), float(y), float(yaw_i)), *labels[i]

    def ground(self, ctx: RobotContext) -> Iterator[ReachablePose]:
        """Checked candidates, best first (lazily: work is done as they are asked for).
        Candidates whose motions between configurations need a planned detour (a straight
        joint-space path collides) come after all the others."""
        ik_checks, passed = 0, 0
        detours = []
        for _, base, arm, grasp in self.candidates(ctx):
            if self.yaws_at(base, arm, grasp) is None:  # (cheap: before the footprint)
                self.rejected["grasp yaw"] += 1
                continue
            if not ctx.base_checker().is_free(*base):
                self.rejected["footprint"] += 1
                continue
            if ik_checks >= (self.max_ik_checks if passed else self.max_ik_checks_if_none):
                break
            ik_checks += 1
            reach = self.reach_from(ctx, base, arm, grasp)
            if reach is None:
                continue
            passed += 1
            if reach.straight:
                yield reach
            else:
                detours.append(reach)
        yield from detours

    def reach_from(self, ctx: RobotContext, base: BasePose, arm: str,
                   grasp: Grasp) -> ReachablePose | None:
        """Every configuration for one base pose, solved and checked (None if one fails)."""
        posed = self.tool_at(base, arm, grasp)
        if posed is None:
            self.rejected["grasp yaw"] += 1
            return None
        target, tool_yaw, item_yaw = posed
        if self.purpose == PICK:
            relative = relative_pose(target, self.point, self.orientation)
            pre = backed_off(target, grasp.kind, PREGRASP_OFFSET_M, PREGRASP_RISE_M)
            post = raised(target, LIFT_M)
            # (pose, holding it?) in the order the checks are cheapest to fail
            poses = {"joints": (target, False), "pre_joints": (pre, False),
                     "post_joints": (post, True)}
        else:
            relative = self.relative
            pre = raised(target, LIFT_M)
            post = backed_off(target, grasp.kind, PREGRASP_OFFSET_M, RETREAT_RISE_M)
            poses = {"joints": (target, True), "pre_joints": (pre, True),
                     "post_joints": (post, False)}
        torso = ctx.scene.joint_positions([TORSO_JOINT])[TORSO_JOINT]
        checks = ConfigurationChecks(ctx, base, arm, self.obj, relative, grasp)
        # keep the torso where it is (it moves at 1.3 cm/s); if that is out of reach or
        # collides, and the torso is not at the table-setting height, let it move there
        keep = [torso] + ([None] if abs(torso - TORSO_UP_M) > 0.01 else [])
        # the last solution's joints seed the solve (it converges in a few steps, near the
        # robot's way of reaching); if that solution is in the way of something, a solve
        # from the reaching start (elbow in, clear of tables) may not be
        seed = ctx.ik_seeds.get((arm, grasp.kind, self.purpose))
        starts = [(fixed, seed) for fixed in keep]
        if seed is not None:
            starts.insert(1, (torso, None))
        for index, (fixed, start) in enumerate(starts):
            solved = self._solve(ctx, arm, grasp, base, fixed, poses, start)
            last = index == len(starts) - 1
            if solved is None:
                if last:
                    self.rejected["ik"] += 1
                    return None
                continue
            # (the configurations with the same hand, as one batch each; placing, the
            # gripper must open at the spot too)
            empty = [solved[key] for key, (_, holding) in poses.items() if not holding]
            full = [solved[key] for key, (_, holding) in poses.items() if holding]
            if self.purpose == PLACE:
                empty.append(solved["joints"])
            free = all(checks.all_free(group, holding)
                       for group, holding in ((empty, False), (full, True)) if group)
            if free:
                break
            if last:
                self.rejected["arm collision"] += 1
                return None
        torso_after = solved["post_joints"][TORSO_JOINT]
        park = (carry_joints(ctx, arm, grasp.kind, grasp.height_m, torso_after)
                if self.purpose == PICK else {**PARK_JOINTS[arm], TORSO_JOINT: torso_after})
        if park is None or not checks.free(park, self.purpose == PICK):
            self.rejected["arm collision"] += 1
            return None
        # the motions the actions will make, each a straight joint-space path?
        pre, at, post = solved["pre_joints"], solved["joints"], solved["post_joints"]
        if self.purpose == PICK:
            arrive = {**PARK_JOINTS[arm], TORSO_JOINT: torso}
            legs = [(arrive, pre, False), (pre, at, False), (at, post, True),
                    (post, park, True)]
        else:
            arrive = carry_joints(ctx, arm, grasp.kind, grasp.height_m, torso) or pre
            legs = [(arrive, pre, True), (pre, at, True), (at, post, False),
                    (post, park, False)]
        straight = all(checks.paths_free([(a, b) for a, b, h in legs if h == holding], holding)
                       for holding in (False, True))
        ctx.ik_seeds[(arm, grasp.kind, self.purpose)] = solved["joints"]
        return ReachablePose(base, arm, grasp, at, pre, post, relative, straight, tool_yaw,
                             item_yaw, tuple(float(v) for v in target.translation))

    def tool_at(self, base: BasePose, arm: str, grasp: Grasp,
                ) -> tuple[pin.SE3, float, float] | None:
        """The tool pose at the grasp (or place) from this base pose, its yaw and the
        item's yaw; None if the grasp needs a tool yaw too far off the robot's heading."""
        yaws = self.yaws_at(base, arm, grasp)
        if yaws is None:
            return None
        tool_yaw, item_yaw = yaws
        if self.purpose == PICK:
            return tool_pose(grasp, self.point, tool_yaw), tool_yaw, item_yaw
        item = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, item_yaw), np.asarray(self.point, float))
        return tool_for_item(item, self.relative), tool_yaw, item_yaw

    def yaws_at(self, base: BasePose, arm: str, grasp: Grasp) -> tuple[float, float] | None:
        """The tool's and the item's yaw at the grasp (or place) from this base pose; None
        if the grasp needs a tool yaw too far off the robot's heading (`tool_at` without
        the pose: candidates are screened with it)."""
        heading = base[2]
        if grasp.kind == "rim":  # the rim point on the arm's side of the item
            heading += math.pi if arm == "right" else 0.0
        if self.purpose == PICK:
            item_yaw = quat_yaw(self.orientation)
            tool_yaw = grasp.tool_yaw(item_yaw, heading)
            return None if tool_yaw is None else (tool_yaw, item_yaw)
        held_yaw = held_item_yaw(self.relative, grasp.kind)  # the item's yaw off the tool's
        if self.target_yaw is None:  # (any yaw will do)
            tool_yaw = heading
        else:
            tool_yaw = grasp.place_yaw(self.target_yaw, held_yaw, heading, self.symmetry_deg)
            if tool_yaw is None:
                return None
        return tool_yaw, tool_yaw + held_yaw

    def _solve(self, ctx: RobotContext, arm: str, grasp: str, base: BasePose,
               torso: float | None, poses: dict[str, tuple[pin.SE3, bool]],
               seed: dict[str, float] | None = None,
               ) -> dict[str, dict[str, float]] | None:
        """IK for the grasp (the torso fixed at `torso`, or None: free, drawn toward the
        table-setting height), then the approach and departure from it on the same torso;
        if those fail from one grasp solution, from another one (a few tries)."""
        ik = arm_ik(arm)
        seed = seed or reaching_seed(arm)
        local = {key: in_base_frame(pose, base) for key, (pose, _) in poses.items()}
        for attempt in range(IK_ATTEMPTS):
            start = seed if attempt == 0 else reaching_seed(arm) if attempt == 1 else None
            at = (ik.solve(local["joints"], ctx.rng, start, fixed_torso_m=torso,
                           restarts=GRASP_IK_RESTARTS)
                  if torso is not None
                  else ik.solve(local["joints"], ctx.rng, start, preferred_torso_m=TORSO_UP_M,
                                restarts=GRASP_IK_RESTARTS))
            if at is None:
                return None  # out of reach: other starts will not help
            solved = {"joints": at.joints}
            for key in ("pre_joints", "post_joints"):
                near = ik.solve(local[key], ctx.rng, at.joints, restarts=1,
                                fixed_torso_m=at.joints[TORSO_JOINT])
                if near is None:
                    break
                solved[key] = near.joints
            else:
                return solved
        return None

    def describe_rejections(self) -> str:
        """What was checked and why it failed, for failure messages."""
        total = sum(self.rejected.values())
        if not total:
            return ""
        parts = ", ".join(f"{n} {REJECTIONS[k]}" for k, n in self.rejected.items() if n)
        kinds = "/".join(dict.fromkeys(str(g) for g in self.grasps))
        return (f"{total} base poses {STANDOFFS_M[0]:.2f}-{STANDOFFS_M[-1]:.2f} m away "
                f"({'/'.join(self.arms)} arm, {kinds} grasp): {parts}")


def held_item_yaw(relative: Relative, kind: str) -> float:
    """The yaw of an item held as `relative` (its pose in the tool frame) when the tool's
    yaw is 0: the item's yaw is the tool's plus this."""
    from cramlite.designators.grasps import TOOL_DOWN

    (_, quat) = relative
    x, y, z, w = quat
    rel = pin.Quaternion(w, x, y, z).toRotationMatrix()
    tool = np.eye(3) if kind == "front" else TOOL_DOWN
    item = tool @ rel
    return math.atan2(item[1, 0], item[0, 0])


#: An arm reaching forward, elbow down (the right arm; the left one mirrored): the IK's
#: first start, so that solutions keep the elbow in, clear of a cupboard's door or sides.
REACHING = {"shoulder_pan_joint": 0.0, "shoulder_lift_joint": 0.4, "upper_arm_roll_joint": 0.0,
            "elbow_flex_joint": -1.2, "forearm_roll_joint": 0.0, "wrist_flex_joint": -0.6,
            "wrist_roll_joint": 0.0}


def reaching_seed(arm: str) -> dict[str, float]:
    side = 1.0 if arm == "right" else -1.0
    mirrored = {"shoulder_pan_joint", "upper_arm_roll_joint", "forearm_roll_joint",
                "wrist_roll_joint"}
    return {f"{arm[0]}_{j}": (v * side if j in mirrored else v) for j, v in REACHING.items()}


def carry_joints(ctx: RobotContext, arm: str, grasp: str, grasp_height: float,
                 torso_m: float) -> dict[str, float] | None:
    """The arm's joints (torso kept) that carry an object grasped with `grasp` upright in
    front of the robot (see `carry_pose`); None if the arm cannot. Of the solutions from
    several starts, the one whose links stick out of the base least low down (so that the
    robot can drive up to a table carrying it; the rest of the robot as it stands now
    counts there too); solved once per world and standing of the rest, from fixed starts."""
    own = {TORSO_JOINT, *arm_joint_names(arm)}
    rest = tuple(round(v, 3) for n, v in sorted(ctx.scene.joint_positions().items())
                 if n not in own)
    key = ("carry", arm, grasp, round(grasp_height, 3), round(torso_m, 3), rest)
    cache = ctx.scene.cache
    if key not in cache:
        # (a pure function of the robot's model and joints: kept for the process too)
        cache[key] = _CARRY.get_or_compute(
            key, lambda: _solve_carry(ctx, arm, grasp, grasp_height, torso_m))
    return cache[key]


def _solve_carry(ctx: RobotContext, arm: str, grasp: str, grasp_height: float,
                 torso_m: float) -> dict[str, float] | None:
    ik = arm_ik(arm)
    rng = np.random.default_rng(0)
    seeds = [{**PARK_JOINTS[arm], TORSO_JOINT: torso_m}, reaching_seed(arm)]
    seeds += [ik.from_q(ik.random_q(rng)) for _ in range(CARRY_STARTS - len(seeds))]
    # the rest of the robot stands the same for every solution (the torso is fixed): what
    # of it sticks out is worked out once, the arm's links for each solution
    parts = upper_body_parts(ctx.scene)
    others = [link for part, (_, links) in parts.items() if part != arm for link in links]
    rest_low: dict[float, float] = {}
    for bottom in (CARRY_BOTTOM_Z_M, *CARRY_LOWER_BOTTOMS_M):  # (highest first)
        best, best_low = None, -np.inf
        for seed in seeds:
            solution = ik.solve(carry_pose(grasp, grasp_height, arm, bottom), rng, seed,
                                fixed_torso_m=torso_m, restarts=0)
            if solution is None:
                continue
            torso = solution.joints[TORSO_JOINT]
            if torso not in rest_low:
                rest_low[torso] = _lowest_outside(ctx, {TORSO_JOINT: torso}, others)
            low = min(rest_low[torso], _lowest_outside(ctx, solution.joints, parts[arm][1]))
            if low > best_low:
                best, best_low = solution.joints, low
        if best is not None:
            return best
    return None


#: Carry poses kept for the process, at most 2 000.
_CARRY: ProcessCache[dict[str, float] | None] = ProcessCache(2_000)


#: IK starts tried for a carry pose.
CARRY_STARTS = 8


def _lowest_outside(ctx: RobotContext, joints: dict[str, float],
                    links: Sequence[str]) -> float:
    """How high the lowest point of these robot links that sticks out of its base square
    is (the robot at the origin), with `joints` (inf: none sticks out)."""
    square = ctx.checker.half_size_m
    lows = [float(pts[np.any(np.abs(pts[:, :2]) > square, axis=1), 2].min())
            for pts in upper_body_points(ctx.scene, list(links), joints=joints)
            if np.any(np.abs(pts[:, :2]) > square)]
    return min(lows, default=np.inf)


class ConfigurationChecks:
    """Checks single configurations of one arm (and the torso) at a base pose, holding the
    object (gripper closed) or not (gripper open); the object being manipulated may be
    touched when not held."""

    def __init__(self, ctx: RobotContext, base: BasePose, arm: str, obj: str,
                 relative: Relative | None, grasp: Grasp | None = None):
        self.ctx = ctx
        self.grasp = grasp
        self.base = base
        self.names = [TORSO_JOINT, *arm_joint_names(arm)]
        self.arm = arm
        self.held = [HeldObject(obj, arm, pose_matrix(*relative))] if relative else []
        self.obj = obj
        self._scenes: dict[bool, object] = {}

    def _scene(self, holding: bool):
        if holding not in self._scenes:
            # what is already in the other hand; the gripper closed on the object while
            # it is held (the fingers touching it), open and clear of it before and after
            others = [h for h in self.ctx.held_objects() if h.name != self.obj]
            closed = self.grasp.closing_angle if self.grasp is not None else None
            self._scenes[holding] = self.ctx.collisions.check(
                self.names, (self.held if holding else []) + others, base=self.base,
                fixed=gripper_joints(self.arm, "close" if holding else "open", closed))
        return self._scenes[holding]

    def _vector(self, joints: dict[str, float]) -> np.ndarray:
        return np.array([joints[n] for n in self.names])

    def free(self, joints: dict[str, float], holding: bool) -> bool:
        return self._scene(holding).is_free(self._vector(joints))

    def all_free(self, configurations: list[dict[str, float]], holding: bool) -> bool:
        """Every one of these configurations free (checked as one batch)."""
        return self._scene(holding).states_free(np.array([self._vector(j)
                                                          for j in configurations]))

    def paths_free(self, paths: list[tuple[dict[str, float], dict[str, float]]],
                   holding: bool) -> bool:
        """Is the straight joint-space path between each of these pairs of checked
        configurations free (all checked as one batch)? (Checked at every fourth step: it
        only ranks candidates, and the motion itself is checked at every step when it is
        executed; on v1-v5 and c1-c3 every fourth step ranks as every second did, the 16
        trials' traces byte-identical, in less time.)"""
        if not paths:
            return True
        limits = self.ctx.limits
        steps = 4 * limits.max_steps(self.names)
        states = []
        for start, goal in paths:
            a = self._vector(start)
            b = limits.unwrap_goal(self.names, a, self._vector(goal))
            states.append(densify(np.vstack([a, b]), steps)[0][1:-1])
        return self._scene(holding).states_free(np.vstack(states))


def held(ctx: RobotContext) -> set[str]:
    return {h.obj for h in ctx.holding.values()}


class PlacingLocation:
    """Free places for an object: at `target` (and offsets around it within the placing
    tolerance), or anywhere on `surface`, nearest to `preferred` first."""

    def __init__(self, obj: ObjectDesignator, target: Vec3 | None = None,
                 surface: str | None = None, preferred: Vec3 | None = None,
                 spot_spacing_m: float = 0.08, edge_margin_m: float = 0.06,
                 clearance_m: float = 0.01):
        if (target is None) == (surface is None):
            raise ValueError("give either a target or a surface")
        self.obj = obj
        self.target = target
        self.surface = surface
        self.preferred = preferred
        self.spot_spacing_m = spot_spacing_m
        self.edge_margin_m = edge_margin_m
        self.clearance_m = clearance_m

    def spots(self, ctx: RobotContext) -> list[Vec3]:
        if self.target is not None:
            tx, ty, tz = self.target
            rings = [(0.0, 1)] + [(r, 8) for r in TARGET_RINGS_M]
            return [(tx + r * math.cos(2 * math.pi * k / n), ty + r * math.sin(2 * math.pi * k / n),
                     tz) for r, n in rings for k in range(n)]
        surf = ctx.scene.surface(self.surface)
        margin = self.edge_margin_m + self.obj.radius_m(ctx)
        xs = np.arange(surf.x_min + margin, surf.x_max - margin + 1e-9, self.spot_spacing_m)
        ys = np.arange(surf.y_min + margin, surf.y_max - margin + 1e-9, self.spot_spacing_m)
        pref = self.preferred or ((surf.x_min + surf.x_max) / 2, (surf.y_min + surf.y_max) / 2,
                                  surf.top_z)
        spots = [(float(x), float(y), surf.top_z) for x in xs for y in ys]
        spots.sort(key=lambda s: math.dist(s[:2], pref[:2]))
        return spots

    def ground(self, ctx: RobotContext) -> Iterator[Vec3]:
        """Spots where the object fits at its most favourable yaw (the exact check, for
        the yaw it will have, is `is_free`)."""
        width = min(object_size(ctx, self.obj.name))
        others = self._others(ctx)
        for spot in self.spots(ctx):
            disc = rectangle(spot[:2], (width, width), 0.0)
            if not any(rectangles_overlap(disc, other, self.clearance_m) for other in others):
                yield spot

    def is_free(self, ctx: RobotContext, spot: Vec3, yaw: float) -> bool:
        """Does the object, put at `spot` with `yaw`, keep clear of every other item?
        (A round object's yaw does not matter.)"""
        if self.obj.is_round(ctx):
            yaw = 0.0
        mine = rectangle(spot[:2], object_size(ctx, self.obj.name), yaw)
        return not any(rectangles_overlap(mine, other, self.clearance_m)
                       for other in self._others(ctx))

    def _others(self, ctx: RobotContext) -> list[np.ndarray]:
        out = []
        for name, item in ctx.scene.items.items():
            if name == self.obj.name or name in held(ctx):
                continue
            (x, y, _), orn = ctx.scene.object_pose(name)
            yaw = 0.0 if item.is_round() else quat_yaw(orn)
            out.append(rectangle((x, y), object_size(ctx, name), yaw))
        return out


def object_size(ctx: RobotContext, name: str) -> tuple[float, float]:
    """Footprint (x, y extent in the object's own frame), however it is held now."""
    extents = ctx.scene.items[name].extents
    return extents[0], extents[1]


def rectangle(centre: Sequence[float], size: tuple[float, float], yaw: float) -> np.ndarray:
    """Corners (4 x 2) of a rectangle of `size` centred at `centre`, turned by `yaw`."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    return local @ np.array([[c, s], [-s, c]]) + np.asarray(centre[:2])


def rectangles_overlap(a: np.ndarray, b: np.ndarray, clearance: float = 0.0) -> bool:
    """Separating-axis test: True unless some edge normal separates them by `clearance`."""
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            axis = np.array([-edge[1], edge[0]]) / np.hypot(*edge)
            pa, pb = a @ axis, b @ axis
            if pa.min() >= pb.max() + clearance or pb.min() >= pa.max() + clearance:
                return False
    return True
