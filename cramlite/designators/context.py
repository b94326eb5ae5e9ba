"""The robot a plan acts through: world, process modules, planners, clock, task tree.

There is no global "current robot": a plan receives a `RobotContext`, made explicitly or
with `simulated_robot(world)`. Which process modules execute its motions is an argument.
The context keeps the robot's clock (driving and arm time of the executed trajectories),
the task tree of what was performed, and, if asked, writes a trace of every state.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.designators.process_modules import ProcessModules, SimulatedProcessModules
from cramlite.designators.tasks import TaskTree
from cramlite.motion.arm_planner import ArmMotionPlanner, ArmPlannerOptions
from cramlite.motion.base_planner import BaseMotionPlanner, BasePlannerOptions
from cramlite.motion.collision import CollisionChecker, HeldObject
from cramlite.motion.footprint import FLOOR_HEIGHT_M, FootprintChecker, OccupancyMap
from cramlite.motion.ik import ARMS, arm_ik, tool_frame
from cramlite.motion.trajectory import (
    ACCELERATION_TIME_S,
    BaseTrajectory,
    JointLimits,
    JointTrajectory,
)
from cramlite.process_cache import ProcessCache
from cramlite.trace.format import TraceWriter
from cramlite.world.bodies import Quat, Vec3
from cramlite.world.world import World

#: The joints a trace records (what cramlite moves), in this order.
TRACE_JOINT_PREFIXES = ("torso_lift_joint", "r_shoulder", "r_upper_arm", "r_elbow", "r_forearm",
                        "r_wrist", "l_shoulder", "l_upper_arm", "l_elbow", "l_forearm",
                        "l_wrist")
FINGER_JOINTS = ("gripper_l_finger_joint", "gripper_r_finger_joint",
                 "gripper_l_finger_tip_joint", "gripper_r_finger_tip_joint")


@dataclass(frozen=True)
class ExecutionOptions:
    """Bounds, tolerances and speeds of plan execution."""

    #: How many candidates (base poses, placements) an action tries before it gives up.
    max_candidates: int = 6
    #: An object counts as placed if it rests within this distance of its target.
    place_tolerance_m: float = 0.05
    #: Longest physics time to let a placed object settle (stops earlier once at rest).
    settle_s: float = 0.3
    #: Robot driving speed (the PR2's 3.6 km/h in the source) and base turn rate.
    drive_speed_m_s: float = 1.0
    turn_speed_rad_s: float = 1.0
    #: Scale of the URDF's joint velocity limits for arm, torso and gripper motions.
    joint_speed_scale: float = 1.0
    #: How fast the gripper pulls or pushes a handle (drawers and doors move gently).
    handle_speed_m_s: float = 0.1
    handle_accel_m_s2: float = 0.2
    #: Leave containers opened to fetch or store an item open until the plan ends (the
    #: plan closes them then); by default each is closed as soon as the item is out (in).
    keep_containers_open: bool = False


@dataclass
class Holding:
    """An object in hand, how it was grasped, and where it came from."""

    obj: str
    grasp: str
    grasp_height_m: float
    #: The object's yaw minus the base yaw it was grasped from: put down from base yaw
    #: psi, it will stand at psi + yaw_offset.
    yaw_offset: float = 0.0
    #: The object's pose in the tool frame (measured when it was grasped).
    relative: tuple[Vec3, Quat] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def robot_limits(world: World, speed_scale: float = 1.0) -> JointLimits:
    """The robot's joint limits from its URDF (velocity scaled; acceleration assumed)."""
    robot = world.robot
    velocity = {n: v * speed_scale for n, v in robot.velocity_limits.items()}
    return JointLimits(
        lower={n: lo for n, (lo, _) in robot.joint_limits.items()},
        upper={n: hi for n, (_, hi) in robot.joint_limits.items()},
        velocity=velocity,
        acceleration={n: v / ACCELERATION_TIME_S for n, v in velocity.items()},
        continuous=frozenset(n for n in robot.joint_index if robot.is_continuous(n)),
        prismatic=frozenset(robot.prismatic))


def _joint_state(world: World) -> tuple[float, ...]:
    """The drawers' and doors' positions, rounded: what the 2D maps depend on."""
    return tuple(round(v, 3) for v in world.world_joint_positions().values())


#: 2D maps kept for the process, at most 48 (about 1 MB each; a map is a pure function of
#: the boxes and outlines it is drawn from).
_MAPS: ProcessCache[OccupancyMap] = ProcessCache(48)


def occupancy_map(world: World, min_top_m: float = 0.0) -> OccupancyMap:
    """The world's 2D map as its drawers and doors stand now (only links whose top is
    above `min_top_m` count), cached per world: by height and joint state, and by the
    links that count (carried objects at many heights share a few maps)."""
    key = ("occupancy", min_top_m, _joint_state(world))
    if key not in world.cache:
        boxes = world.environment_footprints()  # (a door swung open: its outline)
        counted = tuple((name, tuple(np.round(lo, 4)), tuple(np.round(hi, 4)),
                         None if outlines is None else
                         tuple(tuple(np.round(o, 4).ravel()) for o in outlines))
                        for name, lo, hi, outlines in boxes
                        if hi[2] <= FLOOR_HEIGHT_M or hi[2] > max(min_top_m, FLOOR_HEIGHT_M))
        # (maps are kept for the process too, by what they are drawn from: another world
        # of the same kitchen, e.g. the next setup a bench worker loads, reuses them)
        world.cache[key] = _MAPS.get_or_compute(
            counted, lambda: OccupancyMap(boxes, min_top_m=min_top_m))
    return world.cache[key]


def carried_map(world: World, lowest_z: float) -> OccupancyMap:
    """The fixed world that a carried object whose bottom is at `lowest_z` can touch
    (links whose top is above it), by the centimetre."""
    return occupancy_map(world, math.floor(lowest_z * 100) / 100)


def collision_checker(world: World) -> CollisionChecker:
    if "collision" not in world.cache:
        world.cache["collision"] = CollisionChecker(world)
    return world.cache["collision"]


@dataclass
class RobotContext:
    """Everything designators resolve against and motions execute through."""

    world: World
    modules: ProcessModules
    rng: np.random.Generator
    options: ExecutionOptions = field(default_factory=ExecutionOptions)
    planner_options: BasePlannerOptions = field(default_factory=BasePlannerOptions)
    arm_planner_options: ArmPlannerOptions = field(default_factory=ArmPlannerOptions)
    holding: dict[str, Holding] = field(default_factory=dict)
    log: list[str] = field(default_factory=list)
    #: Length of the base paths driven (m), and robot time spent driving / moving joints.
    base_path_m: float = 0.0
    drive_s: float = 0.0
    arm_s: float = 0.0
    trace: TraceWriter | None = None
    #: The xy positions of every executed base trajectory, in order (the driven path).
    driven_xy: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.checker = FootprintChecker(occupancy_map(self.world))
        #: What sticks out of the base (arms, held objects) has changed since the checker
        #: was told (see `base_checker`).
        self.footprint_stale = True
        self.base_planner = BaseMotionPlanner(self.checker, self.planner_options)
        self.collisions = collision_checker(self.world)
        for arm in ARMS:  # the arms' IK models: built once per process, with the robot's
            arm_ik(arm)   # other models (loading, not planning: outside a trial's wall time)
        self.limits = robot_limits(self.world, self.options.joint_speed_scale)
        self.arm_planner = ArmMotionPlanner(self.limits, self.arm_planner_options)
        self.tasks = TaskTree(lambda: self.time_s)
        #: Last IK solution per (arm, grasp): the seed of the next solve.
        self.ik_seeds: dict[tuple[str, str], dict[str, float]] = {}
        #: Containers this context opened and has not closed yet.
        self.opened: list[str] = []
        #: Whole swings of a container no base pose offered to follow, either way:
        #: (container, from, to, arms) with from < to (see `storage._move_stage`).
        self.unfollowable: set[tuple[str, float, float, frozenset[str]]] = set()
        #: Arm motions that needed OMPL (the straight path collided) and all arm motions.
        self.planned_motions = 0
        self.arm_motions = 0
        robot = self.world.robot
        self.trace_joints = [n for n in robot.joint_index
                             if n.startswith(TRACE_JOINT_PREFIXES)
                             or any(n == f"{a}_{f}" for a in "rl" for f in FINGER_JOINTS)]

    @property
    def time_s(self) -> float:
        """Robot time since the plan started: driving plus arm motion."""
        return self.drive_s + self.arm_s

    def note(self, text: str) -> None:
        self.log.append(text)

    def held_objects(self) -> list[HeldObject]:
        return [HeldObject(h.obj, tool_frame(arm), h.relative) for arm, h in self.holding.items()]

    # -- executing trajectories ---------------------------------------------------------
    def drive(self, trajectory: BaseTrajectory) -> None:
        t0 = self.time_s
        self.modules.execute_base_trajectory(trajectory, self._observer(t0, trajectory.times))
        self.base_path_m += trajectory.length_m
        self.driven_xy.append(np.asarray(trajectory.poses)[:, :2].copy())
        self.drive_s += trajectory.duration_s

    def move_joints(self, trajectory: JointTrajectory) -> None:
        t0 = self.time_s
        self.modules.execute_joint_trajectory(trajectory, self._observer(t0, trajectory.times))
        self.arm_s += trajectory.duration_s
        self.footprint_stale = True  # an arm or the torso moved
        if trajectory.world:  # a drawer or door moved: the base planner's map changes
            self.refresh_maps()

    def refresh_maps(self) -> None:
        """Point the base planner at the map of the world as it stands now."""
        self.checker.occupancy = occupancy_map(self.world)
        self.footprint_stale = True  # (what sticks out is checked against maps too)

    def base_checker(self) -> FootprintChecker:
        """The base's footprint check with what sticks out of the base as it is now (the
        arms and what they hold, against the drawers and doors where they stand)."""
        if self.footprint_stale:
            from cramlite.designators.actions import update_carried  # (it imports this)

            update_carried(self)
        return self.checker

    def _observer(self, t0: float, times: np.ndarray):
        if self.trace is None:
            return None
        return lambda i: self.record_state(t0 + float(times[i]))

    def record_state(self, t: float | None = None) -> None:
        """Write the robot's and the objects' current state to the trace (if any)."""
        if self.trace is None:
            return
        joints = self.modules.joint_positions(self.trace_joints)
        objects = {}
        for name in self.world.objects:
            pos, orn = self.modules.object_pose(name)
            objects[name] = [*pos, *orn]
        world_joints = self.modules.world_joint_positions()
        self.trace.write_state(self.time_s if t is None else t, self.modules.base_pose(),
                               [joints[n] for n in self.trace_joints],
                               [world_joints[n] for n in self.world.world_joints],
                               {h.obj: arm for arm, h in self.holding.items()}, objects,
                               self.tasks.current_action())

    def trace_header(self, setup: str, plan: str, strategy: str, seed: int) -> dict[str, Any]:
        return {"setup": setup, "plan": plan, "strategy": strategy, "seed": seed,
                "joints": self.trace_joints, "world_joints": list(self.world.world_joints)}

    def open_trace(self, path: str | Path, setup: str, plan: str, strategy: str,
                   seed: int) -> TraceWriter:
        self.trace = TraceWriter(path, self.trace_header(setup, plan, strategy, seed))
        self.record_state(0.0)
        return self.trace


@contextlib.contextmanager
def simulated_robot(world: World, seed: int | np.random.Generator = 0,
                    options: ExecutionOptions | None = None) -> Iterator[RobotContext]:
    """A context whose motions run in the given PyBullet world."""
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    yield RobotContext(world=world, modules=SimulatedProcessModules(world), rng=rng,
                       options=options or ExecutionOptions())
