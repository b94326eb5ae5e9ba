"""Base paths with OMPL: SE(2) RRTConnect, simplified and interpolated.

States are checked with a `FootprintChecker` (the fixed world in 2D). A straight
line that is free is used as it is, without sampling. Each query reseeds OMPL's random
source from the caller's generator, so the same trial seed gives the same path even in
a worker process that has planned before (OMPL logs an error on reseeding, which is
silenced; the reseed does take effect).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from cramlite.motion.budget import IDLE_ASKS, CheckBudget
from cramlite.motion.footprint import FootprintChecker
from cramlite.motion.trajectory import MAX_BASE_STEP_M, MAX_BASE_TURN_RAD, wrap_angle

BasePose = tuple[float, float, float]  # x, y, yaw


@dataclass(frozen=True)
class BasePlannerOptions:
    #: OMPL's search ends after this many footprint checks (about 30 us each on the
    #: 2-core machine; a budget in work, not seconds, makes a plan's outcome the seed's
    #: alone: `motion.budget`). A query in v1-v5 and c1-c3 needs at most ~330.
    max_checks: int = 20_000
    #: False: reduce vertices and rope-shortcut (~10 ms); True: OMPL's full `simplify`
    #: (~60 ms here, paths ~8 % shorter on detours; it stops on the clock, so with it a
    #: path depends on the host's speed again, not on the seed alone).
    full_simplify: bool = False
    simplify_time_s: float = 0.05
    #: Distance / turn between executed waypoints (every one is checked).
    waypoint_spacing_m: float = MAX_BASE_STEP_M
    waypoint_turn_rad: float = MAX_BASE_TURN_RAD
    #: State-validity checking resolution, as a fraction of the space's extent.
    check_resolution: float = 0.002
    #: The first try's resolution (about 9 cm in the kitchen; the executed waypoints are
    #: all checked anyway, and segments that collide are planned again finely): against
    #: 0.005, planning took 25-30 % less time over v1-v5 and c1-c3, paths as long.
    coarse_check_resolution: float = 0.01
    #: RRTConnect's longest step (m; 0: OMPL's default, a fifth of the space's extent,
    #: about 1.7 m in the kitchen). Long steps mostly end in furniture in narrow passages
    #: (beside an open door): with 1 m, planning took a fifth less time over v1-v5 and
    #: c1-c3, paths 0.5 % longer (and one query beside the open cupboard a quarter of the
    #: checks).
    range_m: float = 1.0


@dataclass(frozen=True)
class BasePath:
    waypoints: list[BasePose]

    @property
    def length_m(self) -> float:
        return path_length_m(self.waypoints)


def path_length_m(waypoints: Sequence[BasePose]) -> float:
    return float(sum(math.dist(a[:2], b[:2]) for a, b in itertools.pairwise(waypoints)))


class BaseMotionPlanner:
    """Plans collision-free base paths in a static 2D world."""

    def __init__(self, checker: FootprintChecker, options: BasePlannerOptions | None = None):
        self.checker = checker
        self.options = options or BasePlannerOptions()
        ou.setLogLevel(ou.LOG_WARN)  # OMPL logs to stdout otherwise

    def plan(self, start: BasePose, goal: BasePose, rng: np.random.Generator) -> BasePath | None:
        """A free path from start to goal, or None if there is none (within the budget of
        checks)."""
        start = (start[0], start[1], wrap_angle(start[2]))
        goal = (goal[0], goal[1], wrap_angle(goal[2]))
        if not (self.checker.is_free(*start) and self.checker.is_free(*goal)):
            return None
        if (straight := self._free_waypoints([start, goal])) is not None:
            return BasePath(straight)
        seed = int(rng.integers(1, 2**31 - 1))
        # OMPL checks its motions coarsely first; every executed waypoint is checked. If one
        # collides, the segments of the path that do are planned again with the fine
        # resolution, and failing that the whole path.
        coarse_resolution = self.options.coarse_check_resolution
        fine_resolution = self.options.check_resolution
        coarse = self._ompl(start, goal, seed, coarse_resolution)
        if coarse is None:
            return None
        if (waypoints := self._free_waypoints(coarse)) is not None:
            return BasePath(waypoints)
        if coarse_resolution != fine_resolution:
            repaired = self._repair(coarse, seed, fine_resolution)
            if repaired is not None and \
                    (waypoints := self._free_waypoints(repaired)) is not None:
                return BasePath(waypoints)
            fine = self._ompl(start, goal, seed, fine_resolution)
            if fine is not None and (waypoints := self._free_waypoints(fine)) is not None:
                return BasePath(waypoints)
        return None

    def _free_waypoints(self, vertices: Sequence[BasePose]) -> list[BasePose] | None:
        """The waypoints along these vertices, if every one is free."""
        waypoints = self._interpolate(vertices)
        return waypoints if self.checker.all_free(waypoints) else None

    def free_path(self, vertices: Sequence[BasePose]) -> list[BasePose] | None:
        """The path through these vertices densified as a planned one is, if every pose
        of it is free; else None (a path given by hand, checked as a planned one)."""
        return self._free_waypoints(vertices)

    def first_blocked(self, vertices: Sequence[BasePose]) -> BasePose | None:
        """The first pose of the densified path through `vertices` that is not free."""
        return next((p for p in self._interpolate(vertices) if not self.checker.is_free(*p)),
                    None)

    def _repair(self, vertices: Sequence[BasePose], seed: int,
                resolution: float) -> list[BasePose] | None:
        """The path with each segment whose waypoints collide planned again between its
        ends; None if one of them has no path, or an end is not free (rope shortcutting
        puts vertices between the states OMPL checked at the coarse resolution)."""
        out = [tuple(vertices[0])]
        for a, b in itertools.pairwise(vertices):
            if self._free_waypoints([a, b]) is not None:
                out.append(tuple(b))
                continue
            detour = self._ompl(a, b, seed, resolution)
            if detour is None:
                return None
            out.extend(detour[1:])
        return out

    def _ompl(self, start: BasePose, goal: BasePose, seed: int,
              resolution: float) -> list[BasePose] | None:
        if not (self.checker.is_free(*start) and self.checker.is_free(*goal)):
            # (OMPL would wait for a valid goal for as long as its termination condition
            # allows, and a budget of checks never ends while nothing is checked: the
            # search would never return)
            return None
        bounds_2d = self.checker.occupancy.bounds
        space = ob.SE2StateSpace()
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(0, bounds_2d.x_min)
        bounds.setHigh(0, bounds_2d.x_max)
        bounds.setLow(1, bounds_2d.y_min)
        bounds.setHigh(1, bounds_2d.y_max)
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        is_free = self.checker.is_free
        budget = CheckBudget(lambda s: is_free(s.getX(), s.getY(), s.getYaw()),
                             self.options.max_checks, idle_asks=IDLE_ASKS)  # (RRTConnect)
        si.setStateValidityChecker(budget)
        si.setStateValidityCheckingResolution(resolution)
        si.setup()
        s, g = si.allocState(), si.allocState()
        s.setX(start[0]), s.setY(start[1]), s.setYaw(start[2])
        g.setX(goal[0]), g.setY(goal[1]), g.setYaw(goal[2])
        pdef = ob.ProblemDefinition(si)
        pdef.setStartAndGoalStates(s, g)
        ou.setLogLevel(ou.LOG_NONE)
        ou.RNG.setSeed(seed)  # see module docstring
        ou.setLogLevel(ou.LOG_WARN)
        planner = og.RRTConnect(si)
        if self.options.range_m:
            planner.setRange(self.options.range_m)
        planner.setProblemDefinition(pdef)
        planner.setup()
        status = planner.solve(budget.condition())
        if status.getStatus() != ob.PlannerStatus.EXACT_SOLUTION:
            return None
        path = pdef.getSolutionPath()
        simplifier = og.PathSimplifier(si)
        if self.options.full_simplify:
            simplifier.simplify(path, self.options.simplify_time_s)
        else:
            simplifier.reduceVertices(path)
            simplifier.ropeShortcutPath(path)
            simplifier.reduceVertices(path)
        # copy the floats out: the states are borrowed from objects that go away
        return [(st.getX(), st.getY(), st.getYaw()) for st in path.getStates()]

    def _interpolate(self, coarse: Sequence[BasePose]) -> list[BasePose]:
        """Waypoints every `waypoint_spacing_m` and `waypoint_turn_rad` (yaw in [-pi, pi):
        OMPL's SE2 bound, a yaw of exactly pi is out of bounds)."""
        out = [tuple(coarse[0])]
        for a, b in itertools.pairwise(coarse):
            dyaw = wrap_angle(b[2] - a[2])
            steps = max(1, math.ceil(max(math.dist(a[:2], b[:2]) / self.options.waypoint_spacing_m,
                                         abs(dyaw) / self.options.waypoint_turn_rad)))
            for i in range(1, steps + 1):
                t = i / steps
                out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                            wrap_angle(a[2] + t * dyaw)))
        return out
