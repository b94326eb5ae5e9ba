"""The robot a plan acts through: world, process modules, solvers, seeded generator.

There is no global "current robot": a plan receives a `RobotContext`, made explicitly or
with `simulated_robot(world)`. Which process modules execute its motions is an argument.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from cramlite.designators.process_modules import ProcessModules, SimulatedProcessModules
from cramlite.motion.base_planner import BaseMotionPlanner, BasePlannerOptions
from cramlite.motion.footprint import FootprintChecker, OccupancyMap
from cramlite.world.world import World

#: Carried objects hang at about this height; lower fixed geometry cannot touch them.
CARRY_BOTTOM_M = 0.95


@dataclass(frozen=True)
class ExecutionOptions:
    """Bounds and tolerances of plan execution."""

    #: How many candidates (base poses, placements) an action tries before it gives up.
    max_candidates: int = 6
    #: An object counts as placed if it rests within this distance of its target.
    place_tolerance_m: float = 0.05
    #: Physics time to let a placed object settle.
    settle_s: float = 0.3
    #: Robot driving speed for robot_time_s (the PR2's 3.6 km/h in the source).
    drive_speed_m_s: float = 1.0


@dataclass
class Holding:
    """An object in hand, how it was grasped, and where it came from."""

    obj: str
    grasp: str
    grasp_height_m: float
    #: The object's yaw minus the base yaw it was grasped from: put down from base yaw
    #: psi, it will stand at psi + yaw_offset.
    yaw_offset: float = 0.0


@dataclass
class RobotContext:
    """Everything designators resolve against and motions execute through."""

    world: World
    modules: ProcessModules
    rng: np.random.Generator
    options: ExecutionOptions = field(default_factory=ExecutionOptions)
    planner_options: BasePlannerOptions = field(default_factory=BasePlannerOptions)
    holding: dict[str, Holding] = field(default_factory=dict)
    log: list[str] = field(default_factory=list)
    base_path_m: float = 0.0

    def __post_init__(self) -> None:
        boxes = self.world.environment_boxes()
        self.checker = FootprintChecker(
            OccupancyMap(boxes), carried_occupancy=OccupancyMap(boxes, min_top_m=CARRY_BOTTOM_M))
        self.base_planner = BaseMotionPlanner(self.checker, self.planner_options)

    def note(self, text: str) -> None:
        self.log.append(text)


@contextlib.contextmanager
def simulated_robot(world: World, seed: int | np.random.Generator = 0,
                    options: ExecutionOptions | None = None) -> Iterator[RobotContext]:
    """A context whose motions run in the given PyBullet world."""
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    yield RobotContext(world=world, modules=SimulatedProcessModules(world), rng=rng,
                       options=options or ExecutionOptions())
