"""One trial: a setup, a plan and a strategy, run headless on a backend; its measurements.

A `TrialRunner` loads the setup's planning scene (checked: an impossible setup is refused
before any trial) and a backend's world once, and resets both between trials (cheap),
which batch workers rely on. The plan plans on the scene and executes through the
backend's process modules; the scene is updated from what they report. Every random
choice follows the trial's seed: the motion layer and the strategy each get a generator
derived from it.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.backends import Backend, default_backend, load_backend
from cramlite.designators import ExecutionOptions, PlanFailure, RobotContext
from cramlite.designators.tasks import time_in
from cramlite.errors import SetupError, UserInputError
from cramlite.plan_names import PLAN_NAMES  # noqa: F401  (re-exported)
from cramlite.plan_registry import crashed, is_builtin, plan_function
from cramlite.plans import PlanReport
from cramlite.scene.scene import PlanningScene
from cramlite.scene.transforms import quat_yaw, yaw_quat
from cramlite.scene.validate import check_setup
from cramlite.strategies import make_strategy
from cramlite.strategies.base import CheckedStrategy, StrategyError
from cramlite.world.setup import Setup, load_setup, resolve_setup_path

RESTING_TOLERANCE_M = 0.01


@dataclass
class TrialResult:
    setup: str
    plan: str
    strategy: str
    seed: int
    success: bool
    order: list[str]
    failures: list[dict[str, Any]]
    base_path_m: float  #: length of the base paths actually driven
    #: sum of straight xy legs robot -> item -> goal (None: a user's plan reported none)
    straight_line_m: float | None
    wall_s: float  #: the host's compute time: planning and executing (loading excluded)
    drive_s: float  #: robot time of the executed base trajectories
    arm_s: float  #: robot time of the executed arm, torso and gripper trajectories
    #: The simulated robot's time from the plan's start to the end of its last motion (the
    #: trace's last t): deterministic for a seed, no host time in it.
    robot_time_s: float
    #: robot_time_s + wall_s: the time of a robot that plans between its motions.
    task_time_s: float = 0.0
    backend: str = ""  #: what executed the trial (see cramlite.backends)
    #: Robot time spent opening and closing drawers and doors (part of drive_s + arm_s).
    open_close_s: float = 0.0
    items: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: The task tree: every action and motion with its robot-time span and status.
    actions: list[dict[str, Any]] = field(default_factory=list)
    #: The driven base path, [[x, y], ...] within 1 cm (see cramlite.trace.path).
    driven_path: list[list[float]] = field(default_factory=list)
    #: Robot time during which two motions ran at once (the torso rising while driving):
    #: robot_time_s = drive_s + arm_s - parallel_s.
    parallel_s: float = 0.0
    #: What the backend's physics measured (`ProcessModules.simulator_report`: physics
    #: steps, the deepest contact while items settled); empty without physics.
    simulator: dict[str, float] = field(default_factory=dict)
    #: Failures injected into the trial, by kind (`--inject`; see
    #: cramlite.designators.injection).
    injected: dict[str, int] = field(default_factory=dict)
    #: Arm motions executed, and how many of them OMPL planned (straight path blocked).
    arm_motions: int = 0
    planned_arm_motions: int = 0
    log: list[str] = field(default_factory=list)
    #: How many items the plan carried at once (`--carry`), and the items fetched
    #: together on each trip, in fetch order.
    carry: int = 1
    trips: list[list[str]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


class TrialRunner:
    """Runs trials of one setup on one backend, resetting its world between trials."""

    def __init__(self, setup: Setup | str, gui: bool = False,
                 options: ExecutionOptions | None = None, backend: str | None = None):
        self.setup = setup if isinstance(setup, Setup) else load_setup(setup)
        self.scene = PlanningScene(self.setup)
        check_setup(self.scene)
        self.backend: Backend = load_backend(backend or default_backend(), self.setup, gui=gui)
        self.options = options or ExecutionOptions()
        self.modules = self.backend.modules

    @property
    def world(self):
        """The backend's own world (a PyBullet `World` for the pybullet backend)."""
        return getattr(self.backend, "world", None)

    def close(self) -> None:
        self.backend.close()

    def __enter__(self) -> TrialRunner:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def run(self, strategy: str = "baseline", plan: str = "set-table", seed: int = 0,
            params: dict[str, float] | None = None, dims: str = "xy",
            order: list[str] | None = None, trace: str | Path | None = None,
            inject: dict[str, float] | None = None, carry: int = 1) -> TrialResult:
        """One trial; `order` replaces the setup's baseline order (for `baseline`);
        `trace`: write every executed state to this file (format cramlite-trace/2);
        `inject`: failure probabilities by kind (cramlite.designators.injection);
        `carry`: how many items the plan carries at once (a plan option: 1 or 2)."""
        plan_fn = plan_function(plan)  # (UserInputError naming --plan if there is none)
        self.backend.reset(self._targets() if plan == "clear-table" else None)
        self.scene.reset()
        chooser = make_strategy(strategy, params=params, dims=dims,
                                rng=np.random.default_rng([seed, 1]),
                                order=list(order or self.setup.baseline_order))
        if not is_builtin(plan):  # (a user's plan calls it directly: checked for it)
            chooser = CheckedStrategy(chooser)
        modules, injector = self.modules, None
        if inject:
            from cramlite.designators.injection import InjectingModules, Injector

            injector = Injector(inject, seed)
            modules = InjectingModules(self.modules, injector)
        ctx = RobotContext(scene=self.scene, modules=modules,
                           rng=np.random.default_rng([seed, 0]), options=self.options,
                           injector=injector, plan_options={"carry": carry})
        ctx.observe()  # (the scene's first belief: what the process modules report)
        if trace is not None:
            ctx.open_trace(trace, self.setup_reference(), plan, strategy, seed,
                           self.backend.name)
        ended = False  # (the plan ran to its end, or failed as plans fail: the trace is whole)
        try:
            start = time.perf_counter()
            try:
                report = plan_fn(ctx, self.setup, chooser)
            except PlanFailure as exc:  # (a user's plan may let one escape)
                report = PlanReport(failures=[exc], success=False)
            except Exception as exc:
                if is_builtin(plan) or isinstance(exc, StrategyError):
                    raise  # (cramlite's own bug, or the strategy's: named as such)
                raise crashed(plan, exc) from exc
            ctx.flush_deferred()  # (a motion the plan deferred to a drive that never came)
            wall_s = time.perf_counter() - start
            ended = True
        finally:
            if ctx.trace is not None:
                ctx.trace.close(complete=ended)
        report = _as_report(report, plan)
        items, success = self._check(plan)
        actions = ctx.tasks.as_list()
        if is_builtin(plan):
            success = success and not report.failures
        else:  # a user's plan says what success is (the items' places are reported)
            success = report.success if report.success is not None else not report.failures
        return TrialResult(
            setup=self.setup.name, plan=plan, strategy=strategy, seed=seed, success=success,
            order=report.order, failures=[f.as_dict() for f in report.failures],
            base_path_m=round(ctx.base_path_m, 6), straight_line_m=_legs(report, plan),
            wall_s=wall_s, drive_s=round(ctx.drive_s, 6), arm_s=round(ctx.arm_s, 6),
            robot_time_s=round(ctx.time_s, 6), task_time_s=round(ctx.time_s + wall_s, 6),
            backend=self.backend.name, items=items,
            open_close_s=round(time_in(actions, ("OpenAction", "CloseAction")), 6),
            actions=actions, driven_path=self._driven_path(ctx), arm_motions=ctx.arm_motions,
            planned_arm_motions=ctx.planned_motions, log=ctx.log,
            parallel_s=round(ctx.overlap_s, 6), simulator=self.modules.simulator_report(),
            injected=dict(injector.injected) if injector is not None else {}, carry=carry,
            trips=report.trips or [[name] for name in report.order])

    def _driven_path(self, ctx: RobotContext) -> list[list[float]]:
        from cramlite.trace.path import simplify_path

        start = self.setup.robot_start
        points = [np.array([[start.x, start.y]]), *ctx.driven_xy]
        return simplify_path(np.concatenate(points))

    def setup_reference(self) -> str:
        """How a trace names this setup: its shipped name, or its file's absolute path."""
        try:
            if resolve_setup_path(self.setup.name).resolve() == self.setup.source.resolve():
                return self.setup.name
        except SetupError:
            pass
        return str(self.setup.source.resolve())

    def _targets(self) -> dict[str, tuple]:
        return {spec.name: (spec.target.xyz, yaw_quat(spec.target.yaw))
                for spec in self.setup.items}

    def _check(self, plan: str) -> tuple[dict[str, dict[str, Any]], bool]:
        """Where each item ended; success = all at their goal and resting, and every
        drawer and door closed."""
        items, success = {}, True
        counter = self.scene.surface("counter")
        for spec in self.setup.items:
            (x, y, z), orientation = self.modules.object_pose(spec.name)
            model = self.scene.items[spec.name].model
            if plan != "clear-table":  # setting the table (or a user's plan): at the targets
                off = math.dist((x, y), (spec.target.x, spec.target.y))
                yaw_off = math.degrees(model.kind.yaw_error(quat_yaw(orientation),
                                                            spec.target.yaw,
                                                            model.yaw_symmetry_deg))
                ok = off <= self.options.place_tolerance_m and \
                    abs(z - spec.target.z) <= RESTING_TOLERANCE_M and \
                    yaw_off <= self.options.yaw_tolerance_deg
                items[spec.name] = {"position": [round(x, 4), round(y, 4), round(z, 4)],
                                    "off_target_m": round(off, 4),
                                    "off_yaw_deg": round(yaw_off, 2), "ok": ok}
            elif spec.container:  # clearing up: back into its drawer or cupboard
                off = math.dist((x, y), (spec.pose.x, spec.pose.y))
                yaw_off = math.degrees(model.kind.yaw_error(quat_yaw(orientation),
                                                            spec.pose.yaw,
                                                            model.yaw_symmetry_deg))
                ok = off <= self.options.place_tolerance_m and \
                    abs(z - spec.pose.z) <= RESTING_TOLERANCE_M and \
                    yaw_off <= self.options.yaw_tolerance_deg
                items[spec.name] = {"position": [round(x, 4), round(y, 4), round(z, 4)],
                                    "off_target_m": round(off, 4),
                                    "off_yaw_deg": round(yaw_off, 2), "ok": ok}
            else:
                ok = counter.contains_xy(x, y) and abs(z - counter.top_z) <= RESTING_TOLERANCE_M
                items[spec.name] = {"position": [round(x, 4), round(y, 4), round(z, 4)], "ok": ok}
            success &= ok
        # every drawer and door is closed again
        success &= all(abs(v) < 1e-3 for v in self.modules.world_joint_positions().values())
        return items, success


def _legs(report: PlanReport, plan: str) -> float | None:
    """The straight-line legs a plan reported: a built-in plan that fetched nothing drove
    none (0 m); a user's plan that never reported any (`PlanReport.add_leg`): None, not a
    distance of 0 that summaries and tests would take for one."""
    legs = report.legs_m()
    if legs is None:
        return 0.0 if is_builtin(plan) else None
    return round(legs, 6)


def _as_report(value: Any, plan: str) -> PlanReport:
    """A plan's return value as a PlanReport (None: nothing to report)."""
    if value is None:
        return PlanReport()
    if isinstance(value, PlanReport):
        return value
    raise UserInputError(f"plan {plan!r} returned {type(value).__name__}; expected a "
                         "PlanReport (from cramlite import PlanReport) or None",
                         field="--plan")


def run_trial(setup: Setup | str, strategy: str = "baseline", plan: str = "set-table",
              seed: int = 0, gui: bool = False, **kwargs: Any) -> TrialResult:
    """One trial in a fresh world."""
    with TrialRunner(setup, gui=gui) as runner:
        return runner.run(strategy, plan, seed, **kwargs)
