"""Motion designators: atomic movements, planned, checked, timed and then executed.

A motion never jumps to its goal: the base follows an OMPL path (states 2 cm apart,
checked against the 2D footprint map), the arm a joint-space path (the straight one if it
is free, else one OMPL plans around obstacles), and each becomes a timed trajectory that
the context's process modules execute state by state. No collision-free path raises
`MotionPlanningFailed`, so the action above can fall through to its next candidate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import (
    GraspFailed,
    MotionPlanningFailed,
    NavigationFailed,
    ObjectNotFound,
    ObjectUnreachable,
    finite_numbers,
)
from cramlite.designators.grasps import in_base_frame
from cramlite.designators.tasks import recorded
from cramlite.motion.base_timing import time_base_path
from cramlite.motion.ik import arm_ik, arm_prefix
from cramlite.motion.trajectory import (
    BaseTrajectory,
    JointTrajectory,
    densify,
    time_along_path,
    time_joint_path,
)
from cramlite.scene.gripper import gripper_geometry
from cramlite.scene.models import pr2_model
from cramlite.scene.scene import gap_to_bounds, shapes_bounds, tool_frame
from cramlite.world.pr2 import ATTACH_REACH_M, HAND_PAYLOAD_KG

BasePose = tuple[float, float, float]
#: The finger joint the others of a gripper follow (see the URDF's mimic tags).
GRIPPER_LEADER = "gripper_l_finger_joint"
#: Open: the finger joint's upper limit (the fingertips 9.2 cm apart); closed on nothing.
GRIPPER_OPEN, GRIPPER_CLOSED = 0.548, 0.0


def move_joints(ctx: RobotContext, joints: dict[str, float], allow_contact: Sequence[str] = (),
                while_driving: bool = False) -> None:
    """Plan, time and execute a joint motion to `joints` (only the joints that change move);
    raises MotionPlanningFailed if no collision-free path is found. `while_driving`: run it
    with the next drive (`RobotContext.defer_to_next_drive`)."""
    check_joint_goal(ctx, joints)
    names = list(joints)
    current = ctx.scene.joint_positions(names)
    start = np.array([current[n] for n in names])
    goal = ctx.limits.unwrap_goal(names, start, np.array([joints[n] for n in names]))
    moving = [i for i in range(len(names)) if abs(goal[i] - start[i]) > 1e-9]
    if not moving:
        return
    names = [names[i] for i in moving]
    start, goal = start[moving], goal[moving]
    check = ctx.collisions.check(names, ignore=allow_contact)
    if check.moves_upright_items and \
            ctx.arm_planner.plan(check, start, goal, ctx.rng, sample=False) is None:
        # the straight joint path tips an upright item (or collides): move the tool along
        # the straight line between its ends, turning only about the vertical, the joints
        # from IK at each step (then OMPL, sampling only upright states, as a last resort)
        kept = upright_path(ctx, check, names, start, goal)
        if kept is not None:
            ctx.arm_motions += 1
            ctx.planned_motions += 1
            ctx.move_joints(kept)
            return
    path = ctx.arm_planner.plan(check, start, goal, ctx.rng)
    why = "" if path is not None else _why(check, start, goal, ctx)
    ctx.arm_motions += 1
    if path is None:
        raise MotionPlanningFailed(f"no collision-free path for {_joint_group(names)}{why}")
    ctx.planned_motions += path.planned
    timed = time_joint_path(names, path.vertices, ctx.limits)
    if while_driving:
        ctx.defer_to_next_drive(timed)
    else:
        ctx.move_joints(timed)


#: How far past a joint limit a goal may lie (rounding in IK and in a user's numbers).
LIMIT_SLACK = 1e-6


def check_joint_goal(ctx: RobotContext, joints: dict[str, float]) -> None:
    """Refuse a goal no motion may reach: a name that is no joint of the robot or a value
    that is no number (ValueError: a mistake in the plan), a value beyond the joint's
    limits from the URDF (MotionPlanningFailed: the motion is impossible; it was driven
    there, and the trace check found the torso at 0.34 m of its 0.31)."""
    limits = ctx.limits
    for name, value in joints.items():
        if name not in limits.lower:
            arm_like = sorted(n for n in limits.lower if not n.endswith("finger_joint")
                              and "gripper" not in n)[:4]
            raise ValueError(f"no joint {name!r} on the robot; expected one of its joints, "
                             f"e.g. {', '.join(arm_like)}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = math.nan
        if not math.isfinite(number):
            raise ValueError(f"{name}: expected a finite number, got {value!r}")
        if name in limits.continuous or name in ctx.scene.robot.followers_of_any:
            continue  # (a finger joint that follows its leader: the URDF's limits are the
            # leader's range, not the follower's, whose multiplier may be -1)
        low, high = limits.lower[name], limits.upper[name]
        if not low - LIMIT_SLACK <= number <= high + LIMIT_SLACK:
            unit = "m" if name in limits.prismatic else "rad"
            raise MotionPlanningFailed(f"{name} to {number:g} {unit} is beyond its limits "
                                       f"[{low:g}, {high:g}] {unit}")


#: The tool's steps along an upright-keeping path (IK at each), and its speed there.
UPRIGHT_STEP_M = 0.02
UPRIGHT_STEP_RAD = 0.08
UPRIGHT_SPEED_M_S = 0.25
UPRIGHT_ACCEL_M_S2 = 0.5
#: A joint that turns further than this between two of its IK steps: the IK switched
#: branches (an elbow flipping), which is no straight tool motion.
UPRIGHT_MAX_JUMP_RAD = 0.3


def upright_path(ctx: RobotContext, check, names: list[str], start: np.ndarray,
                 goal: np.ndarray) -> JointTrajectory | None:
    """A timed joint path of one arm (and the torso) along which its tool moves straight
    from where `start` puts it to where `goal` does, its orientation turned about the
    vertical only (an upright item it holds stays upright), every state checked; None if
    the arm cannot follow that line. Where IK cannot follow the whole line, the part it
    can (from either end) is joined to the other end by the straight joint path, if that
    keeps the item upright and is free too. It may end in another configuration of the
    arm than `goal` that puts the tool at the same pose (IK followed the line there)."""
    arms = {n[0] for n in names if n[:2] in ("r_", "l_")}
    if len(arms) != 1:
        return None
    arm = "right" if arms == {"r"} else "left"
    ik = arm_ik(arm)
    if any(n not in ik.joint_names for n in names):
        return None
    now = ctx.scene.joint_positions(ik.joint_names)
    first = {**now, **dict(zip(names, start, strict=True))}
    last = {**now, **dict(zip(names, goal, strict=True))}
    forward = _follow_line(ctx, ik, arm, names, first, last)
    candidates = [forward]
    if len(forward) < _line_steps(ctx, arm, first, last) + 1:  # IK gave up on the way
        candidates.append(forward + [goal])
        backward = _follow_line(ctx, ik, arm, names, last, first)
        candidates.append([start] + backward[::-1])
    for vertices in candidates:
        if len(vertices) < 2:
            continue
        if np.max(np.abs(goal - vertices[-1])) <= UPRIGHT_MAX_JUMP_RAD:
            vertices = [*vertices[:-1], goal]
        dense, at = densify(np.array(vertices), ctx.limits.max_steps(names))
        if not check.states_free(dense[1:]):
            continue
        # the tool's travel at each dense state, for one speed profile along the way
        tool = f"{arm[0]}_gripper_tool_frame"
        placed = [ctx.scene.link_matrix(tool, {**now, **dict(zip(names, q, strict=True))})
                  for q in vertices]
        steps = [float(np.linalg.norm(b[:3, 3] - a[:3, 3])) + 1e-6
                 for a, b in zip(placed[:-1], placed[1:], strict=True)]
        arc = np.interp(np.arange(len(dense)), at, np.concatenate([[0.0], np.cumsum(steps)]))
        return time_along_path(names, dense, arc, ctx.limits, UPRIGHT_SPEED_M_S,
                               UPRIGHT_ACCEL_M_S2)
    return None


def _line_steps(ctx: RobotContext, arm: str, first: dict[str, float],
                last: dict[str, float]) -> int:
    tool = f"{arm[0]}_gripper_tool_frame"
    a, b = ctx.scene.link_matrix(tool, first), ctx.scene.link_matrix(tool, last)
    turn = float(np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3])))
    distance = float(np.linalg.norm(b[:3, 3] - a[:3, 3]))
    return max(2, int(np.ceil(max(distance / UPRIGHT_STEP_M, turn / UPRIGHT_STEP_RAD))))


def _follow_line(ctx: RobotContext, ik, arm: str, names: list[str], first: dict[str, float],
                 last: dict[str, float]) -> list[np.ndarray]:
    """Joint vectors (in `names` order) along the tool's straight line from where `first`
    puts it toward where `last` does, IK at each step seeded by the step before (the
    torso moving evenly); as far as IK follows without a jump."""
    tool = f"{arm[0]}_gripper_tool_frame"
    a, b = ctx.scene.link_matrix(tool, first), ctx.scene.link_matrix(tool, last)
    turn = pin.log3(a[:3, :3].T @ b[:3, :3])
    steps = _line_steps(ctx, arm, first, last)
    torso = "torso_lift_joint"
    vertices = [np.array([first[n] for n in names])]
    seed = first
    for k in range(1, steps + 1):
        t = k / steps
        rotation = a[:3, :3] @ pin.exp3(t * turn)
        position = a[:3, 3] + t * (b[:3, 3] - a[:3, 3])
        target = in_base_frame(pin.SE3(rotation, position), ctx.scene.base)
        height = first[torso] + t * (last[torso] - first[torso])
        solution = ik.solve(target, ctx.rng, seed, fixed_torso_m=height, restarts=0)
        if solution is None:
            break
        q = np.array([solution.joints[n] for n in names])
        q = ctx.limits.unwrap_goal(names, vertices[-1], q)  # (continuous joints: no spins)
        if np.max(np.abs(q - vertices[-1])) > UPRIGHT_MAX_JUMP_RAD:
            break
        vertices.append(q)
        seed = solution.joints
    return vertices


def _joint_group(names: Sequence[str]) -> str:
    arms = sorted({"right" if n.startswith("r_") else "left" for n in names
                   if n[:2] in ("r_", "l_")})
    parts = [f"the {a} arm" for a in arms] + (["the torso"] if "torso_lift_joint" in names
                                                else [])
    return " and ".join(parts) or "the joints"


def _why(scene, start: np.ndarray, goal: np.ndarray, ctx: RobotContext) -> str:
    contacts = scene.contacts(goal)
    if contacts:
        return f": at the goal {contacts[0].describe()}"
    return (f" within {ctx.arm_planner.options.max_work:,} checks "
            "(the straight path collides and OMPL found no detour)")


@dataclass(frozen=True)
class MoveMotion:
    """Drive the base along a checked path (waypoints x, y, yaw) from where it stands:
    the path from the base's pose through the waypoints is checked at the base
    planner's resolution first (NavigationFailed, naming the first pose that is not
    free, if it is not; nothing moves then)."""

    waypoints: Sequence[BasePose]
    #: The waypoints are a path the base planner checked from where the base stands (as
    #: NavigateAction's are): not checked again. (Not an argument: `_along_checked`.)
    _checked: bool = field(default=False, init=False, repr=False, compare=False)

    @classmethod
    def _along_checked(cls, waypoints: Sequence[BasePose]) -> MoveMotion:
        """A drive along a path the base planner checked from where the base stands."""
        motion = cls(waypoints)
        object.__setattr__(motion, "_checked", True)
        return motion

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        checker = ctx.base_checker()
        waypoints = list(self.waypoints) if self._checked else _free_base_path(
            ctx, self.waypoints)
        # (corners are blended where the footprint check, as the path's, says free)
        timed = time_base_path(waypoints, ctx.options.base_limits, checker.is_free)
        ctx.drive(BaseTrajectory(timed.poses, timed.times))


def _free_base_path(ctx: RobotContext, waypoints: Sequence[BasePose]) -> list[BasePose]:
    """The path from the base's pose through `waypoints`, densified and every pose of it
    free (a path given by hand ran through the counter, and one that did not start
    where the base stood made it jump)."""
    points: list[BasePose] = [finite_numbers(waypoint, 3, f"waypoint {i} (x, y, yaw)")
                              for i, waypoint in enumerate(waypoints)]
    if not points:
        raise ValueError("expected at least one waypoint")
    here = tuple(float(v) for v in ctx.scene.base)
    if math.dist(points[0][:2], here[:2]) > 1e-6 or \
            abs(math.remainder(points[0][2] - here[2], math.tau)) > 1e-6:
        points.insert(0, here)
    free = ctx.base_planner.free_path(points)
    if free is None:
        blocked = ctx.base_planner.first_blocked(points)
        where = "" if blocked is None else (
            f": the base would not fit at ({blocked[0]:.2f}, {blocked[1]:.2f}, "
            f"{math.degrees(blocked[2]):.0f} deg)")
        raise NavigationFailed(f"the base path through {len(points)} waypoints is not "
                               f"free{where}")
    return free


@dataclass(frozen=True)
class MoveArmJointsMotion:
    """Move arm (and torso) joints to angles by name along a collision-free path."""

    joints: dict[str, float]
    #: Objects the motion may touch (the one being grasped or just put down).
    allow_contact: tuple[str, ...] = ()
    #: Move while the base drives next, where that is free (see `move_joints`).
    while_driving: bool = False

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        move_joints(ctx, self.joints, self.allow_contact, self.while_driving)


@dataclass(frozen=True)
class MoveTCPMotion:
    """Move an arm's tool frame to a pose in the world (x, y, z, rotation) via IK."""

    arm: str
    pose: pin.SE3  #: target of the tool frame, world coordinates

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        ik = arm_ik(self.arm)
        target = in_base_frame(self.pose, ctx.scene.base)
        seed = ctx.scene.joint_positions(ik.joint_names)
        solution = (ik.solve(target, ctx.rng, seed, fixed_torso_m=seed["torso_lift_joint"])
                    or ik.solve(target, ctx.rng, seed))
        if solution is None:
            x, y, z = self.pose.translation
            raise ObjectUnreachable(f"no IK solution for the {self.arm} tool frame at "
                                    f"({x:.2f}, {y:.2f}, {z:.2f}) from here")
        move_joints(ctx, solution.joints)


@dataclass(frozen=True)
class MoveTorsoMotion:
    height_m: float
    #: Rise (or sink) while the base drives next, where that is free (see `move_joints`).
    while_driving: bool = False

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        move_joints(ctx, {"torso_lift_joint": self.height_m}, while_driving=self.while_driving)


def gripper_joints(arm: str, state: str, closed_at: float | None = None) -> dict[str, float]:
    """The finger joints of a gripper open or closed (on something: at the finger angle
    `closed_at`, where the fingers touch it): its leading joint and the five that follow
    it (the URDF's mimic tags)."""
    closed = GRIPPER_CLOSED if closed_at is None else closed_at
    value = GRIPPER_OPEN if state == "open" else closed
    return pr2_model().with_mimics({f"{arm_prefix(arm)}_{GRIPPER_LEADER}": value})


@dataclass(frozen=True)
class MoveGripperMotion:
    """Open or close one gripper (its fingers follow a checked trajectory too); closing on
    something `width_m` across, the fingers stop where they touch it."""

    arm: str
    state: str  # "open" | "close"
    allow_contact: tuple[str, ...] = ()
    width_m: float | None = None

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        if self.state not in ("open", "close"):
            raise ValueError(f"gripper state must be 'open' or 'close', got {self.state!r}")
        held = ctx.scene.holding(self.arm)
        if self.state == "open" and held is not None and held not in self.allow_contact:
            # (a place opens the hand on what it puts down, named in allow_contact)
            raise GraspFailed(f"opening the {self.arm} gripper would drop it in the air; "
                              "put it down with PlaceAction", obj=held)
        closed_at = None if self.width_m is None else \
            gripper_geometry().closing_angle(self.width_m)
        move_joints(ctx, gripper_joints(self.arm, self.state, closed_at), self.allow_contact)


@dataclass(frozen=True)
class AttachMotion:
    """The object moves with the gripper from now on. It must be between the gripper's
    fingers (its tool frame within `ATTACH_REACH_M` of the object's bounds), in no other
    hand and no heavier than a hand may hold (`HAND_PAYLOAD_KG`): a gripper does not hold
    what it does not reach or cannot lift (GraspFailed)."""

    arm: str
    obj: str

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        if self.obj not in ctx.scene.items:
            raise ObjectNotFound(f"no such object; expected one of "
                                 f"{', '.join(ctx.scene.items)}", obj=self.obj)
        other = ctx.scene.belief.held.get(self.obj)
        if other is not None and other.arm != self.arm:
            raise GraspFailed(f"already in the {other.arm} hand", obj=self.obj)
        check_payload(ctx, self.obj)
        gap = _tool_gap_m(ctx, self.arm, self.obj)
        if gap > ATTACH_REACH_M:
            raise GraspFailed(f"{gap:.2f} m from the {self.arm} gripper's fingers: it holds "
                              "only what is between them", obj=self.obj)
        ctx.modules.attach(self.arm, self.obj)
        ctx.observe()
        ctx.scene.attach(self.arm, self.obj)
        ctx.footprint_stale = True


@dataclass(frozen=True)
class DetachMotion:
    arm: str
    obj: str

    @recorded
    def perform(self, ctx: RobotContext) -> None:
        held = ctx.scene.belief.held.get(self.obj)
        if held is None or held.arm != self.arm:
            where = "in no hand" if held is None else f"in the {held.arm} hand"
            raise GraspFailed(f"not in the {self.arm} hand ({where})", obj=self.obj)
        ctx.modules.detach(self.arm, self.obj)
        ctx.scene.detach(self.obj)
        holding = ctx.holding.get(self.arm)
        if holding is not None and holding.obj == self.obj:  # (the hand is empty now)
            del ctx.holding[self.arm]
        ctx.observe()
        ctx.footprint_stale = True




def check_payload(ctx: RobotContext, obj: str) -> None:
    """GraspFailed if the object is heavier than one of the PR2's hands may hold
    (`HAND_PAYLOAD_KG`, from its URDF's masses): a red-team setup's 50 kg box was carried
    one-handed."""
    mass = ctx.scene.items[obj].model.mass_kg
    if mass > HAND_PAYLOAD_KG:
        raise GraspFailed(f"{mass:g} kg, more than a hand of the PR2 may hold "
                          f"({HAND_PAYLOAD_KG:g} kg)", obj=obj)


def _tool_gap_m(ctx: RobotContext, arm: str, obj: str) -> float:
    """The distance from the gripper's tool frame to the object's bounds (its own frame:
    0 inside them)."""
    tool = ctx.scene.link_matrix(tool_frame(arm))[:3, 3]
    return gap_to_bounds(tool, ctx.scene.item_matrix(obj),
                         *shapes_bounds(ctx.scene.items[obj].model.shapes))
