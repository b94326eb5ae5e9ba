"""Action designators: what to do, resolved into motions at run time.

Missing parameters (arm, grasp, base pose, place pose) are resolved from location
designators, whose candidates are checked configuration by configuration before they are
offered; the motions between configurations are planned and checked too. Unlike PyCRAM,
a failing candidate is not the end: `TransportAction` goes on to the designator's next
candidate (next base pose, other arm, other grasp, next placement) up to
`ExecutionOptions.max_candidates`, and the failure that finally escapes lists what was
tried.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from cramlite.designators.container_fit import check_fits
from cramlite.designators.context import Holding, RobotContext, carried_map
from cramlite.designators.failures import (
    GraspFailed,
    MotionPlanningFailed,
    NavigationFailed,
    ObjectUnreachable,
    PlacementFailed,
    PlanFailure,
    finite_numbers,
)
from cramlite.designators.grasps import Grasp, item_grasps, relative_pose
from cramlite.designators.locations import (
    PICK,
    PLACE,
    CostmapLocation,
    PlacingLocation,
    ReachablePose,
    carry_joints,
    held,
)
from cramlite.designators.motions import (
    AttachMotion,
    DetachMotion,
    MoveArmJointsMotion,
    MoveGripperMotion,
    MoveMotion,
    MoveTorsoMotion,
    check_payload,
    gripper_joints,
)
from cramlite.designators.objects import ObjectDesignator, ObjectDesignatorDescription, as_object
from cramlite.designators.tasks import ActionDesignator
from cramlite.motion.footprint import convex_hull_2d, following, unique_rows
from cramlite.motion.ik import ARMS
from cramlite.motion.trajectory import wrap_angle
from cramlite.process_cache import ProcessCache
from cramlite.scene.robot_points import upper_body_parts, upper_body_points
from cramlite.world.pr2 import PARK_JOINTS, TORSO_JOINT

BasePose = tuple[float, float, float]
Vec3 = tuple[float, float, float]
GRASP_CHECK_M = 0.03
RESTING_HEIGHT_TOLERANCE_M = 0.01
PARKED_TOLERANCE_RAD = 1e-3
#: Spacing of the points that outline a carried object's footprint (the map has 1 cm cells).
FOOTPRINT_SPACING_M = 0.01
#: The points of what sticks out inside its outline (a link's mesh vertices seen from
#: above, thousands of them) are kept on a grid this fine in the robot's frame, one point a
#: cell: each moves by at most 7.1 mm, well within the map's 2 cm margin, and where an
#: outline meets the furniture the exact check decides anyway (`update_carried`).
STICK_OUT_GRID_M = 0.01


def check_resting_place(ctx: RobotContext, obj: str, point: Vec3) -> None:
    """A place given for an object's bottom centre must have something under it to stand
    on: the top of a surface, or the bottom of a drawer or cupboard (PlacementFailed if
    not: in the air, off an edge, below the floor; no backend would keep it there)."""
    if ctx.scene.support_under(point, RESTING_HEIGHT_TOLERANCE_M) is None:
        x, y, z = point
        raise PlacementFailed(f"the place ({x:.2f}, {y:.2f}, {z:.2f}) rests on nothing (in the "
                              "air, off an edge or below the floor); expected the top of a "
                              "surface or the bottom of a drawer or cupboard under it", obj=obj)


@dataclass
class ParkArmsAction(ActionDesignator):
    """Get the arms ready for driving, one after the other: an empty arm tucked (PyCRAM's
    park pose), an arm holding something in the carry pose (the object upright in front
    of the robot, above the counters). Returns the arms' joint positions where they
    ended (arm -> joint -> rad)."""

    arm: str = "both"  #: "left", "right" or "both"
    #: Park while the base drives next (one combined motion, checked as one; alone first
    #: where the combination collides or no drive comes next).
    while_driving: bool = False

    def __post_init__(self) -> None:
        if self.arm not in (*ARMS, "both"):
            raise ValueError(f"ParkArmsAction: arm must be 'left', 'right' or 'both', got "
                             f"{self.arm!r}")

    def execute(self, ctx: RobotContext) -> dict[str, dict[str, float]]:
        arms = ARMS if self.arm == "both" else (self.arm,)
        for arm in arms:
            target = dict(PARK_JOINTS[arm])
            holding = ctx.holding.get(arm)
            if holding is not None:
                torso = ctx.scene.joint_positions([TORSO_JOINT])[TORSO_JOINT]
                carry = carry_joints(ctx, arm, holding.grasp.kind, holding.grasp.height_m,
                                     torso)
                if carry is not None and _tool_at(ctx, arm, carry):
                    continue  # carried already (another configuration of the arm, maybe)
                target = carry or target
            now = ctx.scene.joint_positions(list(target))
            if any(abs(wrap_angle(now[n] - v)) > PARKED_TOLERANCE_RAD for n, v in target.items()):
                MoveArmJointsMotion(dict(target), while_driving=self.while_driving).perform(ctx)
        return {arm: ctx.scene.joint_positions(list(PARK_JOINTS[arm])) for arm in arms}


def _tool_at(ctx: RobotContext, arm: str, joints: dict[str, float],
             tolerance_m: float = 0.005, tolerance_rad: float = 0.05) -> bool:
    """Is the arm's tool where `joints` would put it?"""
    tool = f"{arm[0]}_gripper_tool_frame"
    now, there = ctx.scene.link_matrix(tool), ctx.scene.link_matrix(tool, joints)
    turn = float(np.linalg.norm(pin.log3(now[:3, :3].T @ there[:3, :3])))
    return float(np.linalg.norm(now[:3, 3] - there[:3, 3])) <= tolerance_m and \
        turn <= tolerance_rad


@dataclass
class MoveTorsoAction(ActionDesignator):
    """Raise or lower the torso; `while_driving`: while the base drives next (one
    combined motion, checked as one; alone first where the combination collides).
    Returns the torso's height where it ended (m)."""

    height_m: float  #: torso lift in metres (0 to 0.31 on the PR2)
    while_driving: bool = False

    def execute(self, ctx: RobotContext) -> float:
        MoveTorsoMotion(self.height_m, self.while_driving).perform(ctx)
        return ctx.scene.joint_positions([TORSO_JOINT])[TORSO_JOINT]

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        torso = ctx.scene.joint_positions([TORSO_JOINT])[TORSO_JOINT]
        if abs(torso - self.height_m) > 1e-3:
            raise MotionPlanningFailed(f"the torso ended at {torso:.3f} m, not "
                                       f"{self.height_m:.3f} m")


@dataclass
class NavigateAction(ActionDesignator):
    """Drive the base to a pose along a collision-free OMPL path; returns where it ended."""

    target: BasePose  #: x, y, yaw in the world

    def __post_init__(self) -> None:
        finite_numbers(self.target, 3, "NavigateAction: target (x, y, yaw)")

    def execute(self, ctx: RobotContext) -> BasePose:
        ctx.base_checker()  # up to date with what sticks out of the base
        start = ctx.scene.base
        path = ctx.base_planner.plan(start, self.target, ctx.rng)
        if path is None:
            x, y, yaw = self.target
            why = ("the base does not fit there (it would hit the kitchen, an item, or "
                   "stick out past the kitchen's walls)"
                   if not ctx.checker.is_free(x, y, yaw) else
                   "none found within the planner's budget" if ctx.checker.is_free(*start)
                   else "the base does not fit where it stands")
            raise NavigationFailed(f"no collision-free base path to ({x:.2f}, {y:.2f}, "
                                   f"{math.degrees(yaw):.0f} deg): {why}")
        MoveMotion._along_checked(path.waypoints).perform(ctx)
        return tuple(ctx.scene.base)  # (where the base ended, as the modules report it)

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        x, y, yaw = ctx.scene.base  # (as the process modules report it)
        off = math.dist((x, y), self.target[:2])
        turn = abs(wrap_angle(yaw - self.target[2]))
        if off > NAVIGATION_TOLERANCE_M or turn > NAVIGATION_TOLERANCE_RAD:
            raise NavigationFailed(f"the base ended {off * 100:.1f} cm and "
                                   f"{math.degrees(turn):.0f} deg from the goal")


#: How close to its goal a navigation must end (the base follows its trajectory exactly
#: in the shipped backends; a robot's localisation is worse).
NAVIGATION_TOLERANCE_M = 0.05
NAVIGATION_TOLERANCE_RAD = 0.1


def _se3(pose: tuple[Vec3, tuple[float, float, float, float]]) -> pin.SE3:
    (x, y, z), (qx, qy, qz, qw) = pose
    return pin.SE3(pin.Quaternion(qw, qx, qy, qz).toRotationMatrix(), np.array([x, y, z]))


@dataclass
class PickUpAction(ActionDesignator):
    """Grasp an object from where the robot stands, lift it and park the arm."""

    object: ObjectDesignator | ObjectDesignatorDescription | str  #: what to pick up
    arms: Sequence[str] | None = None  #: arms to try (default both)
    grasps: Sequence[str] | None = None  #: grasps to try (default by object shape)
    reach: ReachablePose | None = None  #: checked joints from a location designator

    def execute(self, ctx: RobotContext) -> str:
        obj = as_object(self.object, ctx)
        if obj.name in held(ctx):
            hand = next((a for a, h in ctx.holding.items() if h.obj == obj.name), None)
            raise GraspFailed("already held" + (f" in the {hand} hand: put it down with "
                                                "PlaceAction first" if hand else ""),
                              obj=obj.name)
        check_payload(ctx, obj.name)  # (before anything moves)
        reach = self.reach or self._resolve(ctx, obj)
        if reach.arm in ctx.holding:
            raise GraspFailed(f"the {reach.arm} hand is not free", obj=obj.name)
        # the open fingers approach clear of the item (it is not a contact allowed)
        MoveGripperMotion(reach.arm, "open").perform(ctx)
        MoveArmJointsMotion(reach.pre_joints).perform(ctx)
        MoveArmJointsMotion(reach.joints).perform(ctx)
        (bx, by, bz), orientation = obj.pose(ctx)
        tool = ctx.scene.tool_pose(reach.arm)  # (the measured joints' forward kinematics)
        if math.dist(tool[0], reach.tool_position) > GRASP_CHECK_M:
            MoveArmJointsMotion(reach.pre_joints).perform(ctx)
            raise GraspFailed(f"gripper ended {math.dist(tool[0], reach.tool_position) * 100:.1f}"
                              " cm from the grasp point", obj=obj.name)
        # the fingers close until they touch it
        MoveGripperMotion(reach.arm, "close", (obj.name,), width_m=reach.grasp.width_m,
                          ).perform(ctx)
        try:
            AttachMotion(reach.arm, obj.name).perform(ctx)
        except GraspFailed:  # it slipped: open, back off, and let the next candidate try
            MoveGripperMotion(reach.arm, "open", (obj.name,)).perform(ctx)
            MoveArmJointsMotion(reach.pre_joints, (obj.name,)).perform(ctx)
            raise
        ctx.holding[reach.arm] = Holding(
            obj.name, reach.grasp,
            relative=relative_pose(_se3(tool), (bx, by, bz), orientation))
        try:
            MoveArmJointsMotion(reach.post_joints).perform(ctx)  # lift
            ParkArmsAction(reach.arm, while_driving=True).perform(ctx)  # (on the way)
        except PlanFailure:
            self._put_down_again(ctx, reach, obj.name)
            raise
        return reach.arm

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        name = as_object(self.object, ctx).name
        if name not in ctx.scene.held or result not in ctx.holding:
            raise GraspFailed("not in the hand after the pick-up", obj=name)

    def _put_down_again(self, ctx: RobotContext, reach: ReachablePose, name: str) -> None:
        """After a failed lift: back to the grasp, let go, retreat (all checked paths)."""
        try:
            MoveArmJointsMotion(reach.joints).perform(ctx)
            MoveGripperMotion(reach.arm, "open", (name,)).perform(ctx)
            DetachMotion(reach.arm, name).perform(ctx)
            MoveArmJointsMotion(reach.pre_joints, (name,)).perform(ctx)
        except PlanFailure:
            ctx.note(f"could not put {name} down again after a failed lift")

    def _resolve(self, ctx: RobotContext, obj: ObjectDesignator) -> ReachablePose:
        (x, y, z), orientation = obj.pose(ctx)
        base = ctx.scene.base
        tried = []
        for arm in self.arms or [a for a in ARMS if a not in ctx.holding]:
            for grasp in grasps_of(ctx, obj.name, self.grasps):
                location = CostmapLocation((x, y, z), [grasp], obj.name, [arm], PICK,
                                           orientation=orientation)
                reach = location.reach_from(ctx, base, arm, grasp)
                if reach is not None:
                    return reach
                tried.append(f"{arm} arm {grasp} grasp")
        inside = ctx.scene.container_of(obj.name)
        closed = "" if inside is None or ctx.scene.is_open(inside) else (
            f" ({inside.name}, which holds it, is closed: OpenAction({inside.name!r}) "
            "first, or TransportAction, which opens it)")
        raise ObjectUnreachable(f"no arm and grasp reaches it from here{closed}",
                                obj=obj.name, tried=tried)


@dataclass
class PlaceAction(ActionDesignator):
    """Put a held object down at a position from where the robot stands: hover above the
    spot, lower it, let go, retreat, park the arm; returns where it came to rest."""

    object: ObjectDesignator | ObjectDesignatorDescription | str  #: the held object
    target: Vec3  #: where the object's bottom centre goes
    reach: ReachablePose | None = None  #: checked joints from a location designator
    #: The yaw it is to stand at (up to its symmetry); None: any.
    yaw: float | None = None

    def execute(self, ctx: RobotContext) -> Vec3:
        obj = as_object(self.object, ctx)
        arm = next((a for a, h in ctx.holding.items() if h.obj == obj.name), None)
        if arm is None:
            raise PlacementFailed("not held", obj=obj.name)
        if self.reach is None:  # (a location designator's spots stand on a surface)
            check_resting_place(ctx, obj.name, self.target)
        holding = ctx.holding[arm]
        reach = self.reach or self._resolve(ctx, arm, holding)
        MoveArmJointsMotion(reach.pre_joints).perform(ctx)
        MoveArmJointsMotion(reach.joints).perform(ctx)
        touch = (obj.name,)
        MoveGripperMotion(arm, "open", touch).perform(ctx)
        DetachMotion(arm, obj.name).perform(ctx)
        ctx.settle([obj.name])
        ctx.record_state()
        MoveArmJointsMotion(reach.post_joints, touch).perform(ctx)  # retreat
        ParkArmsAction(arm, while_driving=True).perform(ctx)  # (on the way to the next)
        return obj.pose(ctx)[0]  # (where it came to rest)

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        obj = as_object(self.object, ctx)
        if obj.name in ctx.scene.held:
            raise PlacementFailed("still in the hand after placing", obj=obj.name)
        (x, y, z), _ = obj.pose(ctx)
        off = math.dist((x, y), self.target[:2])
        if off > ctx.options.place_tolerance_m or \
                abs(z - self.target[2]) > RESTING_HEIGHT_TOLERANCE_M:
            raise PlacementFailed(f"came to rest at ({x:.2f}, {y:.2f}, {z:.2f}), "
                                  f"{off * 100:.1f} cm from the place pose", obj=obj.name)

    def _resolve(self, ctx: RobotContext, arm: str, holding: Holding) -> ReachablePose:
        location = CostmapLocation(self.target, [holding.grasp], holding.obj, [arm], PLACE,
                                   relative=holding.relative, target_yaw=self.yaw,
                                   symmetry_deg=symmetry_of(ctx, holding.obj))
        reach = location.reach_from(ctx, ctx.scene.base, arm, holding.grasp)
        if reach is None:
            raise ObjectUnreachable("cannot reach the place pose from here", obj=holding.obj)
        return reach


@dataclass
class TransportAction(ActionDesignator):
    """Fetch an object and put it at a target (or on a surface): navigate, pick up,
    navigate, place; each step falls through to the next candidate on failure. If the
    hand that took it cannot put it down, it is put back and the other hand (of `arms`)
    carries it. A drawer or cupboard it is stored in is opened first and closed once it
    is out; one its target is in is opened first too (both hands free), or, for an
    object taken out of another, with the free hand (if that cannot, the object is put
    down, the container opened and the object fetched again). Returns where the object
    came to rest."""

    object: ObjectDesignator | ObjectDesignatorDescription | str  #: what to carry
    target: Vec3 | None = None  #: where its bottom centre goes (or give `surface`)
    surface: str | None = None  #: put it on a free spot of this surface instead
    preferred: Vec3 | None = None  #: with `surface`: spots nearest to this first
    arms: Sequence[str] | None = None  #: arms to consider (default both)
    grasps: Sequence[str] | None = None  #: grasp kinds to consider (default: its item's)
    #: The yaw it is to stand at, at the target (up to its symmetry); None: any.
    target_yaw: float | None = None

    def execute(self, ctx: RobotContext) -> Vec3:
        from cramlite.designators.storage import (
            CloseAction,
            OpenAction,
            container_at,
            container_of,
            is_open,
        )

        obj = as_object(self.object, ctx)
        # a target inside a container is where it is when the container is closed; it
        # rides along with a drawer as that opens
        destination, local = (container_at(ctx, self.target) if self.target is not None
                              else (None, None))
        check_payload(ctx, obj.name)  # (before anything moves)
        if self.target is not None:
            check_resting_place(ctx, obj.name, self.target)
            if destination is not None:  # (at the places around it a transport tries)
                spots = PlacingLocation(obj, target=self.target).spots(ctx)
                check_fits(ctx, obj.name, self.target, spots, destination, self.target_yaw)
        ParkArmsAction().perform(ctx)
        source = container_of(ctx, obj.name)
        if source is not None and not is_open(ctx, source):
            OpenAction(source.name).perform(ctx)  # stored: open its drawer or cupboard first
        target = self.target
        if destination is not None and is_open(ctx, destination):
            target = _at(ctx, destination, local)
        origin, _ = obj.pose(ctx)
        if destination is not None and not is_open(ctx, destination) and source is None:
            # a goal in a closed drawer or cupboard, the item out in the open: open it first,
            # with both hands free (with one hand full, the free one is the one the pick
            # left, and often it cannot: the item was put back and fetched again)
            OpenAction(destination.name).perform(ctx)
            target = _at(ctx, destination, local)
        closed = destination if destination is not None and not is_open(ctx, destination) \
            else None
        try:
            picked_from, planned = self._fetch(ctx, obj, target, closed, local)
        except PlanFailure:
            # not taken out: its drawer or cupboard is not left open in the way of the
            # next transport (closed as after a fetch; a failure to close is noted)
            if source is not None and not ctx.options.keep_containers_open:
                _closed_now(ctx, CloseAction, source)
            raise
        # the item is out: close its container again (with the free hand; if that hand
        # cannot, once the item is delivered)
        to_close = [] if source is None or ctx.options.keep_containers_open else [source]
        to_close = [c for c in to_close if not _closed_now(ctx, CloseAction, c)]
        try:
            if destination is not None and not is_open(ctx, destination):
                try:
                    OpenAction(destination.name).perform(ctx)
                except PlanFailure as failure:
                    # the free hand alone cannot open it: put the item back, open it with
                    # both hands free, and fetch the item again
                    ctx.note(f"cannot open {destination.name} with one hand full "
                             f"({failure}); opening it first")
                    self._put_back(ctx, obj, origin, picked_from)
                    ParkArmsAction().perform(ctx)
                    OpenAction(destination.name).perform(ctx)
                    target = _at(ctx, destination, local)
                    picked_from, planned = self._fetch(ctx, obj, target, None, local)
                target = _at(ctx, destination, local)
            self._deliver(ctx, obj, planned, target)
        except PlanFailure as failure:
            self._with_the_other_hand(ctx, obj, origin, picked_from, failure)
        else:
            if destination is not None and not ctx.options.keep_containers_open:
                to_close.append(destination)  # the item is in: close it
        for container in to_close:  # (what cannot be closed now, the plan closes at its end)
            _closed_now(ctx, CloseAction, container)
        return obj.pose(ctx)[0]  # (where it came to rest)

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        name = as_object(self.object, ctx).name
        if name in ctx.scene.held:
            raise PlacementFailed("still in the hand after the transport", obj=name)

    def _fetch(self, ctx: RobotContext, obj: ObjectDesignator, target: Vec3 | None,
               closed=None, local: Vec3 | None = None,
               ) -> tuple[ReachablePose, tuple[Vec3, ReachablePose] | None]:
        """Navigate and pick up, trying base poses best first; an arm and grasp that could
        not put the object down at the goal are not used. A goal inside a `closed`
        container (at `local` in its inside's frame) is planned as if it were open."""
        from cramlite.designators.storage import container_of, virtually_open
        (x, y, z), orientation = obj.pose(ctx)
        tried: list[str] = []
        last: PlanFailure | None = None
        grasps = _grasps_in(ctx, container_of(ctx, obj.name), z,
                            grasps_of(ctx, obj.name, self.grasps))
        arms = [a for a in (self.arms or ARMS) if a not in ctx.holding]
        location = CostmapLocation((x, y, z), grasps, obj.name, arms, PICK,
                                   orientation=orientation)
        round_object = obj.is_round(ctx)
        deliverable: dict[tuple[str, Grasp, int], tuple[Vec3, ReachablePose] | None] = {}
        attempts = 0
        for reach in location.ground(ctx):
            # held so: the object's yaw off the tool's decides how it can be put down
            held_yaw = reach.item_yaw - reach.tool_yaw
            combo = (reach.arm, reach.grasp, 0 if round_object else round(held_yaw * 18))
            if combo not in deliverable:
                with virtually_open(ctx, closed) if closed else contextlib.nullcontext():
                    goal = _at(ctx, closed, local) if closed else target
                    deliverable[combo] = self._plan_delivery(ctx, obj, reach, goal)
                if deliverable[combo] is None:
                    tried.append(f"{reach.arm} arm {reach.grasp} grasp: could not put it down "
                                 "at the goal")
            planned = deliverable[combo]
            if planned is None:
                continue
            if attempts >= ctx.options.max_candidates:
                break
            attempts += 1
            try:
                NavigateAction(reach.base).perform(ctx)
                PickUpAction(obj, reach=reach).perform(ctx)
                ctx.note(f"picked {obj.name} from {reach.describe()}")
                return reach, planned
            except PlanFailure as failure:
                tried.append(f"{reach.describe()}: {failure.kind}: {failure.reason}")
                last = failure
                ParkArmsAction().perform(ctx)
        rejected = location.describe_rejections()
        if rejected:
            tried.append(rejected)
        cls = type(last) if last is not None else ObjectUnreachable
        reason = last.reason if last is not None else (
            "no arm and grasp that reaches it can put it down at the goal"
            if deliverable and not any(deliverable.values())
            else "no base pose from which an arm reaches it")
        raise cls(reason, obj=obj.name, tried=tried)

    def _plan_delivery(self, ctx: RobotContext, obj: ObjectDesignator, pick: ReachablePose,
                       target: Vec3 | None) -> tuple[Vec3, ReachablePose] | None:
        """A spot of the goal (among its first few free ones) and a checked base pose from
        which the arm of `pick` puts the object down there, held as `pick` would hold it,
        clear of its neighbours."""
        placing = PlacingLocation(obj, target=target, surface=self.surface,
                                  preferred=self.preferred)
        for index, spot in enumerate(placing.ground(ctx)):
            location = CostmapLocation(spot, [pick.grasp], obj.name, [pick.arm], PLACE,
                                       relative=pick.relative, max_ik_checks=12,
                                       target_yaw=self._yaw(target),
                                       symmetry_deg=symmetry_of(ctx, obj.name))
            for reach in location.ground(ctx):
                if placing.is_free(ctx, spot, reach.item_yaw):
                    return spot, reach
            if index >= 2:
                return None
        return None

    def _deliver(self, ctx: RobotContext, obj: ObjectDesignator,
                 planned: tuple[Vec3, ReachablePose] | None = None,
                 target: Vec3 | None = None) -> None:
        """Navigate and place (at `target`, the goal where it is now): first where the
        fetch step found it can, then other spots and base poses, best first."""
        arm = next(a for a, h in ctx.holding.items() if h.obj == obj.name)
        tried: list[str] = []
        last: PlanFailure | None = None
        candidates = self._place_candidates(ctx, obj, arm, planned, target)
        for attempt, (spot, reach) in enumerate(candidates):
            if attempt >= ctx.options.max_candidates:
                break
            where = f"spot ({spot[0]:.2f}, {spot[1]:.2f})"
            if reach is None:
                tried.append(f"{where}: no reachable base pose")
                continue
            try:
                NavigateAction(reach.base).perform(ctx)
                PlaceAction(obj, spot, reach=reach, yaw=self._yaw(target)).perform(ctx)
                ctx.note(f"placed {obj.name} at ({spot[0]:.3f}, {spot[1]:.3f}) from "
                         f"{reach.describe()}")
                return
            except PlanFailure as failure:
                tried.append(f"{where} from {reach.describe()}: {failure.kind}: {failure.reason}")
                last = failure
                if obj.name not in held(ctx):
                    break  # it is no longer in hand
                ParkArmsAction(arm).perform(ctx)
        reason = last.reason if last is not None else "no reachable free place"
        raise PlacementFailed(reason, obj=obj.name, tried=tried)

    def _place_candidates(self, ctx: RobotContext, obj: ObjectDesignator, arm: str,
                          planned: tuple[Vec3, ReachablePose] | None, target: Vec3 | None,
                          ) -> Iterator[tuple[Vec3, ReachablePose | None]]:
        """(spot, base pose) to try, best first: the plan from the fetch step, then each
        free spot with its base poses (None: the spot has no reachable one)."""
        if planned is not None:
            yield planned
        holding = ctx.holding[arm]
        placing = PlacingLocation(obj, target=target, surface=self.surface,
                                  preferred=self.preferred)
        for spot in placing.ground(ctx):
            location = CostmapLocation(spot, [holding.grasp], obj.name, [arm], PLACE,
                                       relative=holding.relative, max_ik_checks=12,
                                       target_yaw=self._yaw(target),
                                       symmetry_deg=symmetry_of(ctx, obj.name))
            found = False
            for reach in location.ground(ctx):
                if placing.is_free(ctx, spot, reach.item_yaw):
                    found = True  # else, put down from there, it would touch a neighbour
                    yield spot, reach
            if not found:
                yield spot, None

    def _yaw(self, target: Vec3 | None) -> float | None:
        """The yaw to put it down at: the target yaw, where there is a target."""
        return self.target_yaw if target is not None else None

    def _with_the_other_hand(self, ctx: RobotContext, obj: ObjectDesignator, origin: Vec3,
                             picked_from: ReachablePose, failure: PlanFailure) -> None:
        """After a failed delivery: put the object back and transport it with the other
        hand (of `arms`, if free), which also delivers it (and closes what it opens); if
        it cannot be put back, or there is no other hand, or that fails too, raise."""
        arm = picked_from.arm
        others = [a for a in (self.arms or ARMS) if a != arm and a not in ctx.holding]
        if obj.name in held(ctx):
            ctx.note(f"could not put {obj.name} down with the {arm} arm ({failure.kind}: "
                     f"{failure.reason}); putting it back")
        put_down = self._put_back(ctx, obj, origin, picked_from)
        if not put_down or not others:  # (not where it could be taken from again)
            raise failure
        # the goal was reachable with this hand, but not the way there (e.g. into a
        # cupboard past its side wall): the other hand takes it from where it is now
        ctx.note(f"taking {obj.name} with the {' or '.join(others)} arm")
        ParkArmsAction().perform(ctx)
        try:
            replace(self, object=obj, arms=others).perform(ctx)
        except PlanFailure as second:
            raise type(second)(second.reason, obj=obj.name, tried=[
                f"{arm} arm: {failure.kind}: {failure.reason}", *failure.tried,
                f"{' or '.join(others)} arm: {second.kind}: {second.reason}",
                *second.tried]) from second

    def _put_back(self, ctx: RobotContext, obj: ObjectDesignator, origin: Vec3,
                  picked_from: ReachablePose) -> bool:
        """After a failed delivery nothing stays in hand: put the object back where it was
        taken from (from the same base pose, the pick's own checked configurations in
        reverse), else on the same surface (or, if it came out of a drawer or cupboard
        closed since, the nearest surface an item of the setup stands on outside them), as
        near to it as it can, or, if even that fails, let go of it. True if it was put
        down."""
        arm = next((a for a, h in ctx.holding.items() if h.obj == obj.name), None)
        if arm is None:
            return False
        from cramlite.designators.storage import container_at, is_open

        inside, _ = container_at(ctx, origin)
        shut = inside is not None and not is_open(ctx, inside)  # (its door closed since)
        try:
            try:
                if shut:
                    raise PlacementFailed(f"{inside.name} is closed now", obj=obj.name)
                # (where it was may be in the air now: its drawer closed since)
                check_resting_place(ctx, obj.name, origin)
                NavigateAction(picked_from.base).perform(ctx)
                # (a new IK solution for the same spot may be another elbow, one that
                # touches the table: the pick's own solution did not)
                undo = replace(picked_from, pre_joints=picked_from.post_joints,
                               post_joints=picked_from.pre_joints,
                               relative=ctx.holding[arm].relative)
                PlaceAction(obj, origin, reach=undo).perform(ctx)
            except PlanFailure:
                surface = _surface_near(ctx, origin, under=not shut)
                if obj.name not in held(ctx) or surface is None:
                    raise
                ParkArmsAction(arm).perform(ctx)
                beside = TransportAction(obj, surface=surface, preferred=origin, arms=[arm])
                beside._deliver(ctx, obj)
            (x, y, _), _ = obj.pose(ctx)
            ctx.note(f"put {obj.name} back at ({x:.2f}, {y:.2f})")
            return True
        except PlanFailure as failure:
            if arm in ctx.holding:
                DetachMotion(arm, obj.name).perform(ctx)
                ctx.settle([obj.name])
                ctx.note(f"let go of {obj.name} (could not put it back: {failure.reason})")
            return False
        finally:
            ctx.footprint_stale = True


def _surface_near(ctx: RobotContext, point: Vec3, under: bool = True) -> str | None:
    """The surface under a point (with `under`), else the one nearest to it (in x and y)
    of those the setup's items stand on outside drawers and cupboards."""
    below = ctx.scene.surface_under(*point, RESTING_HEIGHT_TOLERANCE_M) if under else None
    if below is not None:
        return below.name
    names = sorted({spec.surface for spec in ctx.scene.setup.items if not spec.container})

    def away(name: str) -> float:
        surf = ctx.scene.surface(name)
        dx = max(surf.x_min - point[0], 0.0, point[0] - surf.x_max)
        dy = max(surf.y_min - point[1], 0.0, point[1] - surf.y_max)
        return math.hypot(dx, dy)

    return min(names, key=away, default=None)


def _closed_now(ctx: RobotContext, close, container) -> bool:
    """Try to close a container this context opened; a failure is noted, not raised."""
    if container.name not in ctx.opened:
        return True
    try:
        close(container.name).perform(ctx)
        return True
    except PlanFailure as failure:
        ctx.note(f"left {container.name} open for now: {failure}")
        return False


def _at(ctx: RobotContext, container, local: Vec3) -> Vec3:
    """A point given in a container's inside frame, in the world as it is believed to
    stand now."""
    return ctx.scene.inside_point(container, local)


def grasps_of(ctx: RobotContext, name: str, kinds: Sequence[str] | None = None,
              ) -> list[Grasp]:
    """An item's grasps (of `kinds` only, if given), in order of preference."""
    grasps = item_grasps(ctx.scene.items[name].model)
    if kinds is None:
        return grasps
    chosen = [g for g in grasps if g.kind in kinds]
    if not chosen:
        raise GraspFailed(f"no {'/'.join(kinds)} grasp fits it (its grasps: "
                          f"{', '.join(dict.fromkeys(g.kind for g in grasps))})", obj=name)
    return chosen


def symmetry_of(ctx: RobotContext, name: str) -> float:
    """Degrees of a turn about +z that leave the item the same (0: any)."""
    return ctx.scene.items[name].model.yaw_symmetry_deg


def _grasps_in(ctx: RobotContext, container, bottom_z: float,
               grasps: list[Grasp]) -> list[Grasp]:
    """The grasps for an object, without the front grasps where the object lies in a
    drawer whose sides rise above them (the fingers would have to pass through them:
    every base pose would be tried and fail)."""
    if container is None or container.kind != "drawer":
        return grasps
    rim = _at(ctx, container, container.inside_max)[2]
    kept = [g for g in grasps if g.kind != "front" or
            bottom_z + g.height_m >= rim + FINGER_CLEARANCE_M]
    return kept or grasps


#: The fingers of a front grasp keep at least this much above a drawer's sides.
FINGER_CLEARANCE_M = 0.02


def footprint_outline(points_xy: np.ndarray, spacing: float) -> np.ndarray:
    """Points every `spacing` along the convex hull of 2D points (a carried object's or a
    link's footprint as seen from above)."""
    pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    hull = convex_hull_2d(pts)
    if len(hull) < 3 or abs(_area(hull)) < 1e-12:  # fewer than 3 points, or all on a line
        return unique_rows(np.round(pts, 6))
    # n points on each edge a -> b, from a (inclusive) towards b (exclusive)
    edges = following(hull) - hull
    n = np.maximum(1, np.ceil(np.hypot(edges[:, 0], edges[:, 1]) / spacing)).astype(int)
    edge = np.repeat(np.arange(len(hull)), n)
    step = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    return hull[edge] + (step / n[edge])[:, None] * edges[edge]


def _area(polygon: np.ndarray) -> float:
    """Signed area of a polygon (shoelace)."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, following(y)) - np.dot(y, following(x)))


def update_carried(ctx: RobotContext) -> None:
    """Tell the base planner what sticks out of the base while it drives: every carried
    object (its box seen from above) and every arm link that reaches beyond the base
    square (from its collision mesh; a parked PR2's elbows stick out 0.43 m to the sides),
    each as an outline in the robot's frame checked against the furniture that rises above
    the lowest point that sticks out."""
    x, y, yaw = ctx.scene.base
    c, s = math.cos(yaw), math.sin(yaw)
    groups: dict[float, list[np.ndarray]] = {}
    held = {holding.obj for holding in ctx.holding.values()}
    for name in held:
        corners = _item_corners(ctx, name)
        dx, dy = corners[:, 0] - x, corners[:, 1] - y
        robot_frame = np.column_stack([c * dx + s * dy, -s * dx + c * dy, corners[:, 2]])
        _stick_out(robot_frame, ctx.checker.half_size_m, groups)
    for bucket, points in _upper_body_outline(ctx, set(ARMS)).items():
        groups.setdefault(bucket, []).append(points)
    # the items standing (the maps hold the kitchen only): each one's xy box and top
    standing = [_item_corners(ctx, name) for name in ctx.scene.items if name not in held]
    boxes = np.array([[*k[:, :2].min(axis=0), *k[:, :2].max(axis=0)] for k in standing])
    tops = np.array([k[:, 2].max() for k in standing])
    ctx.checker.set_carried([(np.vstack(points), carried_map(ctx.scene, bucket),
                              boxes[tops > bucket] if len(standing) else np.zeros((0, 4)))
                             for bucket, points in sorted(groups.items())],
                            _exact_upper_body(ctx) if groups else None)
    ctx.footprint_stale = False


def _item_corners(ctx: RobotContext, name: str) -> np.ndarray:
    """The eight corners (world frame) of an item's box as it stands or is held."""
    ex, ey, ez = ctx.scene.items[name].extents
    local = np.array([[sx * ex / 2, sy * ey / 2, sz * ez] for sx in (-1, 1)
                      for sy in (-1, 1) for sz in (0, 1)])
    frame = ctx.scene.item_matrix(name)
    return local @ frame[:3, :3].T + frame[:3, 3]


def _exact_upper_body(ctx: RobotContext):
    """A check of the robot's upper body and carried objects, as they are now, at another
    base pose, against the kitchen and the items (the planning scene's exact test):
    exact where the 2D outlines are coarse."""
    check = ctx.collisions.check(["torso_lift_joint"], self_collision=False)
    q = check.current()
    return lambda x, y, yaw: check.is_free_at((x, y, yaw), q)


def _stick_out(points: np.ndarray, square: float, groups: dict[float, list[np.ndarray]],
               ) -> None:
    """Add the outline of what of `points` (robot frame, x y z) lies beyond the base
    square, under the height of its lowest such point (rounded down to 5 cm)."""
    out = np.any(np.abs(points[:, :2]) > square, axis=1)
    if not out.any():
        return  # within the base's square: the base's check covers it
    bucket = math.floor(float(points[out, 2].min()) * 20) / 20  # 5 cm: few maps
    outline = footprint_outline(points[:, :2], FOOTPRINT_SPACING_M)
    outline = outline[np.any(np.abs(outline) > square, axis=1)]
    inside = np.round(points[out, :2] / STICK_OUT_GRID_M) * STICK_OUT_GRID_M
    groups.setdefault(bucket, []).append(np.vstack([outline, inside]))


def _upper_body_outline(ctx: RobotContext, arms: set[str]) -> dict[float, np.ndarray]:
    """What of the links of `arms` sticks out of the base in the current configuration
    (robot frame, by height); computed once per configuration of the arm (and the torso)
    and world."""
    joints = ctx.scene.joint_positions()
    out: dict[float, list[np.ndarray]] = {}
    for part, (names, links) in upper_body_parts(ctx.scene).items():
        if part not in arms:
            continue
        key = ("outline", part, tuple(round(joints[n], 2) for n in names))
        if key not in ctx.scene.cache:
            # (a pure function of the robot's model: kept for the process too)
            ctx.scene.cache[key] = _OUTLINES.get_or_compute(
                key, lambda links=links: _part_outline(ctx, links))
        for bucket, points in ctx.scene.cache[key].items():
            out.setdefault(bucket, []).append(points)
    return {b: np.vstack(p) for b, p in out.items()}


def _part_outline(ctx: RobotContext, links: list[int]) -> dict[float, np.ndarray]:
    """What of these robot links sticks out of the base as they stand (by height)."""
    groups: dict[float, list[np.ndarray]] = {}
    for points in upper_body_points(ctx.scene, links):  # (the base at the origin)
        _stick_out(points, ctx.checker.half_size_m, groups)
    # (the links' points on the grid: one a cell, also where two links overlap)
    return {b: unique_rows(np.vstack(p)) for b, p in groups.items()}


#: Outlines of the arms (and torso and head) kept for the process, at most 5 000.
_OUTLINES: ProcessCache[dict[float, np.ndarray]] = ProcessCache(5_000)


@dataclass
class SetGripperAction(ActionDesignator):
    """Open or close an empty gripper (its fingers along a checked, timed trajectory). A
    gripper holding something is refused: letting go is PlaceAction's (where it lands is
    checked there). Returns the gripper's joint positions where they ended (rad)."""

    arm: str  #: "left" or "right"
    state: str  #: "open" or "close"

    def execute(self, ctx: RobotContext) -> dict[str, float]:
        if self.arm not in ARMS or self.state not in ("open", "close"):
            raise ValueError(f"SetGripperAction: expected arm in {ARMS} and state 'open' or "
                             f"'close', got {self.arm!r} and {self.state!r}")
        holding = ctx.holding.get(self.arm)
        if holding is not None:
            raise GraspFailed(f"the {self.arm} gripper holds {holding.obj}: put it down with "
                              "PlaceAction", obj=holding.obj)
        MoveGripperMotion(self.arm, self.state).perform(ctx)
        return ctx.scene.joint_positions(list(gripper_joints(self.arm, self.state)))

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        wanted = gripper_joints(self.arm, self.state)
        now = ctx.scene.joint_positions(list(wanted))
        off = max(abs(now[n] - v) for n, v in wanted.items())
        if off > 0.01:
            raise MotionPlanningFailed(f"the {self.arm} gripper ended {off:.3f} rad from "
                                       f"{self.state}")


@dataclass
class PickAndPlaceAction(ActionDesignator):
    """Pick an object up and put it at `target` from where the robot stands (no driving:
    TransportAction drives); returns where it came to rest."""

    object: ObjectDesignator | ObjectDesignatorDescription | str
    target: tuple[float, float, float]
    arms: Sequence[str] = ARMS

    def execute(self, ctx: RobotContext) -> object:
        obj = as_object(self.object, ctx)
        PickUpAction(obj, arms=list(self.arms)).perform(ctx)
        return PlaceAction(obj, self.target).perform(ctx)

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        obj = as_object(self.object, ctx)
        (x, y, _), _ = ctx.scene.object_pose(obj.name)
        off = math.dist((x, y), self.target[:2])
        if obj.name in ctx.scene.held or off > ctx.options.place_tolerance_m:
            raise PlacementFailed(f"it ended {off * 100:.1f} cm from the target", obj=obj.name)
