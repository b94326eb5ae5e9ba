"""The robot a plan acts through: planning scene, process modules, planners, clock, tasks.

There is no global "current robot": a plan receives a `RobotContext`, made explicitly or
with `simulated_robot(setup)`. Designators ask the context's planning scene about the
world (never the world that executes); the process modules execute the motions planned
on it and report the world back, and the scene is updated from their reports after every
motion. The context keeps the robot's clock (driving and arm time of the executed
trajectories), the task tree of what was performed, and, if asked, writes a trace of
every state.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.backends.base import Backend, ProcessModules
from cramlite.designators.failures import PlanFailure
from cramlite.designators.grasps import Grasp
from cramlite.designators.monitors import Watch, first_firing
from cramlite.designators.tasks import TaskTree
from cramlite.motion.arm_planner import ArmMotionPlanner, ArmPlannerOptions
from cramlite.motion.base_planner import BaseMotionPlanner, BasePlannerOptions
from cramlite.motion.base_timing import BaseLimits
from cramlite.motion.footprint import FLOOR_HEIGHT_M, FootprintChecker, OccupancyMap
from cramlite.motion.ik import ARMS, arm_ik
from cramlite.motion.trajectory import (
    ACCELERATION_TIME_S,
    BaseTrajectory,
    JointLimits,
    JointTrajectory,
)
from cramlite.process_cache import ProcessCache
from cramlite.scene.collision import HeldObject, SceneCollisions
from cramlite.scene.scene import PlanningScene
from cramlite.scene.transforms import Quat, Vec3
from cramlite.trace.format import TraceWriter
from cramlite.world.setup import Setup

#: The joints a trace records (what cramlite moves): the torso, the head, both arms, and
#: every finger joint of both grippers (six each, moving together: the mimic tags).
TRACE_JOINT_PREFIXES = ("torso_lift_joint", "head_pan_joint", "head_tilt_joint", "r_shoulder",
                        "r_upper_arm", "r_elbow", "r_forearm", "r_wrist", "r_gripper",
                        "l_shoulder", "l_upper_arm", "l_elbow", "l_forearm", "l_wrist",
                        "l_gripper")


@dataclass(frozen=True)
class ExecutionOptions:
    """Bounds, tolerances and speeds of plan execution."""

    #: How many candidates (base poses, placements) an action tries before it gives up.
    max_candidates: int = 6
    #: An object counts as placed if it rests within this distance of its target, turned
    #: within this angle of its target yaw (up to its symmetry: a round one at any).
    place_tolerance_m: float = 0.05
    yaw_tolerance_deg: float = 10.0
    #: Longest physics time to let a placed object settle (stops earlier once at rest).
    settle_s: float = 0.3
    #: Robot driving speed (the PR2's 3.6 km/h in the source) and base turn rate, and
    #: their accelerations (an assumption: see cramlite.motion.base_timing).
    drive_speed_m_s: float = 1.0
    turn_speed_rad_s: float = 1.0
    drive_accel_m_s2: float = 1.0
    turn_accel_rad_s2: float = 1.5
    #: Scale of the URDF's joint velocity limits for arm, torso and gripper motions.
    joint_speed_scale: float = 1.0
    #: How fast the gripper pulls or pushes a handle (drawers and doors move gently).
    handle_speed_m_s: float = 0.1
    handle_accel_m_s2: float = 0.2
    #: Leave containers opened to fetch or store an item open until the plan ends (the
    #: plan closes them then); by default each is closed as soon as the item is out (in).
    keep_containers_open: bool = False
    #: Run motions on disjoint joint groups at once where a plan asks for it and the
    #: combined states are free (the torso rising while the base drives); off: one after
    #: the other, as before.
    parallel_motion: bool = True

    def __post_init__(self) -> None:
        """Speeds, accelerations, tolerances and times are positive finite numbers (a NaN
        acceleration left braking no profile to fit); counts are whole numbers >= 1."""
        for name in ("place_tolerance_m", "yaw_tolerance_deg", "settle_s", "drive_speed_m_s",
                     "turn_speed_rad_s", "drive_accel_m_s2", "turn_accel_rad_s2",
                     "joint_speed_scale", "handle_speed_m_s", "handle_accel_m_s2"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or \
                    not math.isfinite(value) or value <= 0:
                raise ValueError(f"ExecutionOptions.{name}: expected a finite number > 0, "
                                 f"got {value!r}")
        if isinstance(self.max_candidates, bool) or not isinstance(self.max_candidates, int) \
                or self.max_candidates < 1:
            raise ValueError(f"ExecutionOptions.max_candidates: expected a whole number >= 1, "
                             f"got {self.max_candidates!r}")

    @property
    def base_limits(self) -> BaseLimits:
        return BaseLimits(self.drive_speed_m_s, self.turn_speed_rad_s, self.drive_accel_m_s2,
                          self.turn_accel_rad_s2)


@dataclass
class Holding:
    """An object in hand, how it was grasped, and where it came from."""

    obj: str
    grasp: Grasp
    #: The object's pose in the tool frame (measured when it was grasped).
    relative: tuple[Vec3, Quat] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def robot_limits(scene: PlanningScene, speed_scale: float = 1.0) -> JointLimits:
    """The robot's joint limits from its URDF (velocity scaled; acceleration assumed)."""
    joints = scene.robot.joints
    velocity = {n: j.velocity * speed_scale for n, j in joints.items()}
    return JointLimits(
        lower={n: j.lower for n, j in joints.items()},
        upper={n: j.upper for n, j in joints.items()},
        velocity=velocity,
        acceleration={n: v / ACCELERATION_TIME_S for n, v in velocity.items()},
        continuous=frozenset(n for n, j in joints.items() if j.kind == "continuous"),
        prismatic=frozenset(n for n, j in joints.items() if j.kind == "prismatic"))


def _joint_state(scene: PlanningScene) -> tuple[float, ...]:
    """The drawers' and doors' positions, rounded: what the 2D maps depend on."""
    return tuple(round(v, 3) for v in scene.world_joint_positions().values())


#: 2D maps kept for the process, at most 48 (about 1 MB each; a map is a pure function of
#: the boxes and outlines it is drawn from).
_MAPS: ProcessCache[OccupancyMap] = ProcessCache(48)


def occupancy_map(scene: PlanningScene, min_top_m: float = 0.0) -> OccupancyMap:
    """The kitchen's 2D map as its drawers and doors are believed to stand (only links
    whose top is above `min_top_m` count), cached per scene: by height and joint state,
    and by the links that count (carried objects at many heights share a few maps)."""
    key = ("occupancy", min_top_m, _joint_state(scene))
    if key not in scene.cache:
        boxes = scene.environment_footprints()  # (a door swung open: its outline)
        counted = tuple((name, tuple(np.round(lo, 4)), tuple(np.round(hi, 4)),
                         None if outlines is None else
                         tuple(tuple(np.round(o, 4).ravel()) for o in outlines))
                        for name, lo, hi, outlines in boxes
                        if hi[2] <= FLOOR_HEIGHT_M or hi[2] > max(min_top_m, FLOOR_HEIGHT_M))
        # (maps are kept for the process too, by what they are drawn from: another scene
        # of the same kitchen, e.g. the next setup a bench worker loads, reuses them)
        scene.cache[key] = _MAPS.get_or_compute(
            counted, lambda: OccupancyMap(boxes, min_top_m=min_top_m))
    return scene.cache[key]


def carried_map(scene: PlanningScene, lowest_z: float) -> OccupancyMap:
    """The fixed world that a carried object whose bottom is at `lowest_z` can touch
    (links whose top is above it), by the centimetre."""
    return occupancy_map(scene, math.floor(lowest_z * 100) / 100)


def scene_collisions(scene: PlanningScene) -> SceneCollisions:
    if "collision" not in scene.cache:
        scene.cache["collision"] = SceneCollisions(scene)
    return scene.cache["collision"]


def _group(names: Sequence[str]) -> str:
    arms = sorted({n[0] for n in names if n[:2] in ("l_", "r_")})
    parts = [{"l": "left arm", "r": "right arm"}[a] for a in arms]
    parts += [n for n in names if n[:2] not in ("l_", "r_")]
    return " and ".join(parts)


#: The combined states of a parallel motion are checked at least this often (s): 2 cm of
#: driving at full speed.
CHECK_STEP_S = 0.02


def _dense(base: BaseTrajectory, joints: JointTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """Base poses and joint states of a combined motion every CHECK_STEP_S (and at its
    own states), interpolated linearly as execution moves between states."""
    times = np.asarray(base.times, dtype=float)
    grid = np.sort(np.concatenate([times, np.arange(0.0, times[-1], CHECK_STEP_S)]))
    grid = grid[np.concatenate([[True], grid[1:] != grid[:-1]])]  # (np.union1d, whose
    # first call imports numpy.ma: 15 ms a process)
    poses = np.asarray(base.poses, dtype=float).copy()
    poses[:, 2] = np.unwrap(poses[:, 2])
    positions = np.asarray(joints.positions, dtype=float)
    dense_poses = np.column_stack([np.interp(grid, times, poses[:, k]) for k in range(3)])
    dense_q = np.column_stack([np.interp(grid, times, positions[:, k])
                               for k in range(positions.shape[1])])
    return dense_poses, dense_q


def _combined(base: BaseTrajectory, joints: JointTrajectory, start_s: float,
              ) -> tuple[BaseTrajectory, JointTrajectory, float]:
    """A drive starting `start_s` after a joint motion, both sampled at the same times:
    the joints' before the drive and after it, the drive's own during it (each holding
    its first state before it starts and its last after it ends)."""
    base_times = np.asarray(base.times, dtype=float) + start_s
    joint_times = np.asarray(joints.times, dtype=float)
    times = np.concatenate([joint_times[joint_times < start_s], base_times,
                            joint_times[joint_times > base_times[-1]]])
    poses = np.asarray(base.poses, dtype=float)
    before = int(np.sum(joint_times < start_s))
    after = len(times) - before - len(base_times)
    combined_poses = np.concatenate([np.repeat(poses[:1], before, axis=0), poses,
                                     np.repeat(poses[-1:], after, axis=0)])
    # (on the joints' own profile at the drive's times: interpolated straight between its
    # states, the joints would change speed in a jump at each one)
    q = joints.at_times(times)
    return (BaseTrajectory(combined_poses, times),
            JointTrajectory(tuple(joints.names), q, times), start_s)


@dataclass
class Deferred:
    """A joint motion waiting for the next drive, and the task nodes (its motion and
    action) whose robot-time span is when it really runs."""

    trajectory: JointTrajectory
    nodes: list[Any]

    def span(self, start_s: float, end_s: float) -> None:
        for node in self.nodes:
            node.start_s, node.end_s = start_s, end_s


@dataclass
class RobotContext:
    """Everything designators resolve against (the planning scene) and motions execute
    through (the process modules)."""

    scene: PlanningScene
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
    #: Robot time during which two motions ran at once (counted once in `time_s`).
    overlap_s: float = 0.0
    #: Joint motions planned to run while the base drives next (`defer_to_next_drive`).
    deferred: list[Deferred] = field(default_factory=list)
    #: Seeded failure injection of the trial (`cramlite.designators.injection`), if any.
    injector: Any = None
    #: Inside a `Parallel`: joint motions wait for the next drive (see `deferring`).
    defer_joint_motions: bool = False
    #: The plan's options, as `run` and `bench` pass them (`carry`: how many items to
    #: carry at once); a plan reads the ones it uses.
    plan_options: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.checker = FootprintChecker(occupancy_map(self.scene))
        #: What sticks out of the base (arms, held objects) has changed since the checker
        #: was told (see `base_checker`).
        self.footprint_stale = True
        self.base_planner = BaseMotionPlanner(self.checker, self.planner_options)
        self.collisions = scene_collisions(self.scene)
        for arm in ARMS:  # the arms' IK models: built once per process, with the robot's
            arm_ik(arm)   # other models (loading, not planning: outside a trial's wall time)
        self.limits = robot_limits(self.scene, self.options.joint_speed_scale)
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
        self.trace_joints = [n for n in self.scene.robot.joints
                             if n.startswith(TRACE_JOINT_PREFIXES)]
        #: The monitors watching every state of every motion now (see `Monitor`).
        self.monitors: list[Watch] = []

    def __repr__(self) -> str:  # (the dataclass's would print every driven path point)
        x, y, yaw = self.scene.base
        held = {arm: h.obj for arm, h in self.holding.items()}
        return (f"RobotContext(setup={self.scene.setup.name!r}, base=({x:.2f}, {y:.2f}, "
                f"{math.degrees(yaw):.0f} deg), holding={held}, robot_time={self.time_s:.1f} s, "
                f"driven={self.base_path_m:.2f} m, modules={type(self.modules).__name__})")

    @property
    def time_s(self) -> float:
        """Robot time since the plan started: driving plus arm motion, the time of motions
        that ran at once counted once."""
        return self.drive_s + self.arm_s - self.overlap_s

    def note(self, text: str) -> None:
        self.log.append(text)

    def held_objects(self) -> list[HeldObject]:
        return [HeldObject(name, held.arm, held.relative)
                for name, held in self.scene.held.items()]

    def observe(self) -> None:
        """Update the planning scene from what the process modules report (a joint motion
        deferred to the next drive is believed done: what is planned next plans with it)."""
        self.scene.observe(self.modules)
        for d in self.deferred:
            self.scene.belief.joints.update(d.trajectory.final())

    def settle(self, objects: list[str]) -> None:
        """Let released objects come to rest (physics, where the backend has it), then
        observe where they are."""
        self.modules.settle(self.options.settle_s, objects)
        self.observe()

    # -- executing trajectories ---------------------------------------------------------
    def drive(self, trajectory: BaseTrajectory) -> None:
        if self.deferred:
            if not self.monitors and self._drive_in_parallel(trajectory):
                return
            self.flush_deferred()
        t0 = self.time_s
        fired = None
        if self.monitors:
            trajectory, fired = self._watched_base(trajectory)
        if len(trajectory.poses):
            self.modules.execute_base_trajectory(trajectory,
                                                 self._observer(t0, trajectory.times))
        self.observe()
        self._count_drive(trajectory)
        if fired is not None:
            raise fired

    def _count_drive(self, trajectory: BaseTrajectory) -> None:
        """Add an executed drive to the path driven and the driving time."""
        self.base_path_m += trajectory.length_m
        self.driven_xy.append(np.asarray(trajectory.poses)[:, :2].copy())
        self.drive_s += trajectory.duration_s

    def move_joints(self, trajectory: JointTrajectory) -> None:
        if self.defer_joint_motions and not self.deferred and self._can_defer(trajectory):
            self.defer_to_next_drive(trajectory)  # (inside a Parallel: with the next drive)
            return
        self.flush_deferred()  # (a deferred motion runs first, where it was planned)
        self._execute_joints(trajectory)

    @contextlib.contextmanager
    def deferring(self) -> Iterator[None]:
        """Within: a joint motion waits for the next drive and runs with it (see
        `Parallel`); at the end, whatever still waits runs."""
        before, self.defer_joint_motions = self.defer_joint_motions, True
        try:
            yield
        finally:
            self.defer_joint_motions = before
        if not before:
            self.flush_deferred()

    def _execute_joints(self, trajectory: JointTrajectory) -> None:
        t0 = self.time_s
        fired = None
        if self.monitors:
            trajectory, fired = self._watched_joints(trajectory)
        if len(trajectory.positions):
            self.modules.execute_joint_trajectory(trajectory,
                                                  self._observer(t0, trajectory.times))
        self.observe()
        self.arm_s += trajectory.duration_s
        self.footprint_stale = True  # an arm or the torso moved
        if trajectory.world:  # a drawer or door moved: the base planner's map changes
            self.refresh_maps()
        if fired is not None:
            raise fired

    # -- parallel motion ----------------------------------------------------------------
    def defer_to_next_drive(self, trajectory: JointTrajectory) -> None:
        """Run a planned joint motion (the torso's) while the base drives next: believed
        done from now, executed with the next drive if the two are free together at every
        combined state, else alone before whatever moves next (where it was planned and
        checked: nothing has moved since). Without `parallel_motion`, or while monitors
        watch, it runs now."""
        if not self._can_defer(trajectory):
            self.move_joints(trajectory)
            return
        self.flush_deferred()  # (one at a time)
        now = self.time_s
        nodes = [n for n in self.tasks.open_nodes() if n.start_s == now]
        self.deferred.append(Deferred(trajectory, nodes))
        self.scene.belief.joints.update(trajectory.final())
        self.footprint_stale = True

    def _can_defer(self, trajectory: JointTrajectory) -> bool:
        """May a joint motion wait for the next drive: parallel motion on, no monitor
        watching, no drawer or door moving with it, and something to move?"""
        return self.options.parallel_motion and not self.monitors \
            and not trajectory.world and len(trajectory.positions) > 0

    def flush_deferred(self) -> None:
        """Execute deferred joint motions now, one after the other."""
        while self.deferred:
            d = self.deferred.pop(0)
            t0 = self.time_s
            self._execute_joints(d.trajectory)
            d.span(t0, t0 + d.trajectory.duration_s)

    def _drive_in_parallel(self, trajectory: BaseTrajectory) -> bool:
        """Drive with the deferred motion at once if the combined states are free: the
        drive starting with the joint motion, or a quarter, a half or three quarters of
        it later (an arm first swinging clear of the counter it reached over); sampled at
        the joints' times before and after the drive and at the drive's own times during
        it (resampling a timed base path would bend it), checked together, sent together.
        False (nothing done) if no start is free."""
        d = self.deferred[0] if len(self.deferred) == 1 else None
        if d is None or not len(trajectory.poses):
            return False
        joints = d.trajectory
        # against the kitchen and the items (the joint path is the one planned and checked
        # against the robot itself, which does not depend on where the base is), at the
        # sent states and between them every CHECK_STEP_S
        check = self.collisions.check(list(joints.names), self_collision=False)
        for delay in (0.0, 0.25, 0.5, 0.75):
            combined = _combined(trajectory, joints, delay * joints.duration_s)
            if check.states_free_along(*_dense(*combined[:2])):
                break
        else:
            self.note(f"{_group(joints.names)} not moved while driving: every combined "
                      "motion collides")
            return False
        self.deferred.clear()
        t0 = self.time_s
        combined_base, combined_joints, start = combined
        try:
            self.modules.execute_parallel(combined_base, combined_joints,
                                          self._observer(t0, combined_base.times,
                                                         ["base", *joints.names]))
        except PlanFailure:  # (refused before anything moved: the joint motion still waits)
            self.deferred.append(d)
            self.observe()
            raise
        self.observe()
        self._count_drive(trajectory)
        self.arm_s += joints.duration_s
        self.overlap_s += max(0.0, min(joints.duration_s - start, trajectory.duration_s))
        self.footprint_stale = True
        d.span(t0, t0 + joints.duration_s)
        return True

    # -- monitors -----------------------------------------------------------------------
    def _latched(self):
        return next((w.fired for w in self.monitors if w.fired is not None), None)

    def _watched_base(self, trajectory: BaseTrajectory):
        """The trajectory as the monitors let it run (braked where one fires)."""
        from cramlite.motion.braking import brake_base_trajectory

        if (latched := self._latched()) is not None:
            return BaseTrajectory(np.zeros((0, 3)), np.zeros(0)), latched
        joints = self.scene.joint_positions()
        poses = np.asarray(trajectory.poses, dtype=float)
        k = first_firing(self.monitors, self.time_s, trajectory.times,
                         lambda i: tuple(float(v) for v in poses[i]), lambda i: joints,
                         tuple(self.scene.held))
        if k is None:
            return trajectory, None
        braked = brake_base_trajectory(trajectory, k, self.options.base_limits)
        return braked, self._fired_on(trajectory, braked)

    def _watched_joints(self, trajectory: JointTrajectory):
        from cramlite.motion.braking import brake_joint_trajectory

        if (latched := self._latched()) is not None:
            return JointTrajectory(trajectory.names, np.zeros((0, len(trajectory.names))),
                                   np.zeros(0)), latched
        now = self.scene.joint_positions()
        base = tuple(self.scene.base)
        positions = np.asarray(trajectory.positions, dtype=float)

        def joints_at(i: int) -> dict[str, float]:
            return {**now, **dict(zip(trajectory.names, positions[i].tolist(), strict=True))}

        k = first_firing(self.monitors, self.time_s, trajectory.times, lambda i: base,
                         joints_at, tuple(self.scene.held))
        if k is None:
            return trajectory, None
        braked = brake_joint_trajectory(trajectory, k, self.limits)
        return braked, self._fired_on(trajectory, braked)

    def _fired_on(self, trajectory, braked):
        """The MonitorFired to raise after a motion a watch stopped: where braking kept
        the motion (it was at rest sooner at its own end), saying so."""
        if braked is trajectory:
            for watch in self.monitors:
                if watch.fired is not None:
                    watch.ran_to_its_end(self.time_s + float(trajectory.times[-1]))
        return self._latched()

    def refresh_maps(self) -> None:
        """Point the base planner at the map of the kitchen as it is believed to stand."""
        self.checker.occupancy = occupancy_map(self.scene)
        self.footprint_stale = True  # (what sticks out is checked against maps too)

    def base_checker(self) -> FootprintChecker:
        """The base's footprint check with what sticks out of the base as it is now (the
        arms and what they hold, against the drawers and doors where they stand)."""
        if self.footprint_stale:
            from cramlite.designators.actions import update_carried  # (it imports this)

            update_carried(self)
        return self.checker

    def _observer(self, t0: float, times: np.ndarray, parallel: list[str] | None = None):
        if self.trace is None:
            return None
        return lambda i: self.record_state(t0 + float(times[i]), parallel)

    def record_state(self, t: float | None = None, parallel: list[str] | None = None) -> None:
        """Write the robot's and the objects' current state to the trace (if any)."""
        if self.trace is None:
            return
        joints = self.modules.joint_positions(self.trace_joints)
        objects = {}
        for name in self.scene.items:
            pos, orn = self.modules.object_pose(name)
            objects[name] = [*pos, *orn]
        world_joints = self.modules.world_joint_positions()
        self.trace.write_state(self.time_s if t is None else t, self.modules.base_pose(),
                               [joints[n] for n in self.trace_joints],
                               [world_joints[n] for n in self.scene.kitchen.joints],
                               {h.obj: arm for arm, h in self.holding.items()}, objects,
                               self.tasks.current_action(), parallel)

    def trace_header(self, setup: str, plan: str, strategy: str, seed: int,
                     backend: str = "") -> dict[str, Any]:
        from cramlite import __version__
        from cramlite.scene.models import file_digest

        robot = self.scene.robot
        return {"setup": setup, "plan": plan, "strategy": strategy, "seed": seed,
                "joints": self.trace_joints, "world_joints": list(self.scene.kitchen.joints),
                "backend": backend, "cramlite": __version__,
                "setup_hash": self.scene.setup.content_hash,
                "robot": {"urdf": str(robot.urdf), "sha256": file_digest(robot.urdf),
                          "joint_limits": {n: [j.lower if math.isfinite(j.lower) else None,
                                               j.upper if math.isfinite(j.upper) else None,
                                               j.velocity]
                                           for n, j in robot.joints.items()
                                           if n in self.trace_joints}},
                "base_limits": asdict(self.options.base_limits)}

    def open_trace(self, path: str | Path, setup: str, plan: str, strategy: str,
                   seed: int, backend: str = "") -> TraceWriter:
        self.trace = TraceWriter(path, self.trace_header(setup, plan, strategy, seed,
                                                         backend))
        self.record_state(0.0)
        return self.trace


@contextlib.contextmanager
def simulated_robot(setup: Setup | Backend | Any, seed: int | np.random.Generator = 0,
                    options: ExecutionOptions | None = None,
                    backend: str | None = None) -> Iterator[RobotContext]:
    """A context whose motions run in a backend's world of the setup (default: the
    default backend), planned on a scene of the setup. Instead of a setup, a backend
    already loaded (or a PyBullet `World`) may be given: it is not closed afterwards."""
    from cramlite.backends import default_backend, load_backend

    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    owned = isinstance(setup, Setup)
    if owned:
        world = load_backend(backend or default_backend(), setup)
    elif isinstance(setup, Backend):
        world = setup
    else:  # a PyBullet World
        from cramlite.backends.pybullet import PyBulletBackend

        world = PyBulletBackend.around(setup)
    try:
        scene = PlanningScene(world.setup)
        ctx = RobotContext(scene=scene, modules=world.modules, rng=rng,
                           options=options or ExecutionOptions())
        ctx.observe()
        ended = False
        try:
            try:
                yield ctx
            except PlanFailure:  # (a plan's failure: every state was written, as a trial's)
                ended = True
                raise
            ctx.flush_deferred()  # (a motion deferred to a drive that never came)
            ended = True
        finally:
            if ctx.trace is not None:  # (opened with `open_trace`: whole if it ended)
                ctx.trace.close(complete=ended)
    finally:
        if owned:
            world.close()
