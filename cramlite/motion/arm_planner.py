"""Collision-free joint-space paths for the arms (and torso) with OMPL.

The straight joint-space path is tried first (checked state by state, densest where a
collision is likeliest: bisection order). If it collides, a path through one of a few
waypoints of the arm (`arm_waypoints.json`: where OMPL's detours on the shipped setups went,
learned by `benchmarks/learn_arm_waypoints.py`) is tried, each leg straight and checked at
every step the same way; if none is free, OMPL's RRTConnect plans in the space of the
moving joints against the same `CollisionScene` (each motion it tries
checked as one batch of states: `_SegmentChecks`), then the path is shortened
(vertex reduction and rope shortcutting, which keep it valid) and every state of the
densified result is checked again, so what is executed is exactly what was checked.

Joints are planned in normalised units (each joint divided by its largest allowed step),
so one validity-checking resolution gives the trajectory's density for revolute and
prismatic joints alike. Continuous joints are unwrapped to turn the short way.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from cramlite.motion.budget import IDLE_ASKS, CheckBudget
from cramlite.motion.ik import ARMS, arm_joint_names, arm_prefix
from cramlite.motion.trajectory import JointLimits, densify
from cramlite.scene.collision import MotionCheck as CollisionScene

#: OMPL plans keeping this much further from obstacles than the final check requires, so
#: the densified path (whose states lie between OMPL's) passes that check.
PLANNING_MARGIN_M = 0.003


@dataclass(frozen=True)
class ArmPlannerOptions:
    """Settings of the joint-space planner (pyroboplan style: options beside the solver)."""

    #: OMPL's search ends after this much work: states checked plus exact pair tests
    #: made (20 000 is 0.5-1.2 s on the 2-core machine; a budget in work, not seconds,
    #: makes a plan's outcome the seed's alone: `motion.budget`).
    max_work: int = 20_000
    #: Try the straight joint-space path before sampling.
    try_straight: bool = True
    #: Shorten a sampled path (OMPL's vertex reduction).
    shorten: bool = True
    #: OMPL checks motions every this many allowed steps (the densified result is then
    #: checked at every step, and planned again finely if it collides): coarser sampling
    #: plans faster (4 against 2: a fifth less OMPL time over v1-v5 and c1-c3).
    check_every_steps: float = 4.0
    #: The OMPL planner class (og.<name>) and its range in allowed steps (0: default).
    planner: str = "RRTConnect"
    range_steps: float = 0.0
    #: The range for a motion that moves an upright item (0: `range_steps`). Most states
    #: tip such an item, so the default range (a fifth of the space's extent, 45-55 steps)
    #: mostly proposes extensions that tip it somewhere: over clearing up c3 (seeds 0-2)
    #: 2 of 18 such searches found a path within the budget, 14 of 18 with 16 steps.
    upright_range_steps: float = 16.0
    #: OMPL's path may take an upright held item at most this far below the lower of its
    #: two ends (None: anywhere; the straight path and the learned waypoints' detours are
    #: not held to it). Short steps anywhere in the joint space wander: without a floor,
    #: the paths into c3's cupboard swung the milk from the table's height down to
    #: 0.33-0.48 m on its way to a shelf at 1.0 m.
    upright_drop_m: float | None = 0.15
    #: Such a search first samples each joint only within this far (rad, or m for the
    #: torso) of the box its start and goal span, and searches anywhere only if that
    #: fails (0: anywhere at once).
    upright_box: float = 0.6
    #: Before OMPL, try the paths through the arm's learned waypoints (`arm_waypoints`):
    #: on the shipped setups they find a free detour for 5 in 6 of the motions OMPL
    #: plans, in milliseconds where OMPL takes tenths of a second.
    waypoints: bool = True

    def __post_init__(self) -> None:
        if self.upright_drop_m is not None and not self.upright_drop_m >= 0:
            raise ValueError(f"ArmPlannerOptions.upright_drop_m: expected a distance >= 0 "
                             f"(or None), got {self.upright_drop_m!r}")
        if not self.upright_box >= 0:
            raise ValueError(f"ArmPlannerOptions.upright_box: expected a distance >= 0, "
                             f"got {self.upright_box!r}")


WAYPOINTS_FILE = Path(__file__).with_name("arm_waypoints.json")


@functools.cache
def arm_waypoints() -> dict[tuple[str, ...], tuple[np.ndarray, ...]]:
    """The learned waypoints of each arm (values of its seven joints, `arm_joint_names`
    order), keyed by those joints' names, in the order they are tried."""
    data = json.loads(WAYPOINTS_FILE.read_text(encoding="utf-8"))
    return {tuple(arm_joint_names(arm)):
            tuple(np.array(w, dtype=float) for w in data["arms"][arm_prefix(arm)])
            for arm in ARMS}


#: Planners that check motions only whole (OMPL's `checkMotion(s1, s2)`), so that
#: `_SegmentChecks` can check each motion's states as one batch (not those that ask where
#: a motion stops being valid, e.g. the KPIECE family or TRRT: its binding never says).
SEGMENT_PLANNERS = frozenset({"RRTConnect"})
#: Planners whose search a budget may also end when it is asked to stop again and again
#: with no work done (`motion.budget.IDLE_ASKS`): those that ask once a step, on the
#: searching thread, and check something in every step.
IDLE_CHECKED_PLANNERS = frozenset({"RRTConnect"})


class _SegmentChecks(ob.MotionValidator):
    """OMPL's motion check with each motion's states checked as one batch: the states of
    OMPL's discrete motion validator (every `every` normalised units up to and with the
    end), one broadphase for all of them, then exact tests (the end first, then in
    bisection order) up to the first collision; the same answers as checking them one by
    one, at about a third of the cost. The budget counts the states checked one by one
    would have been, up to the first that collides."""

    def __init__(self, si: ob.SpaceInformation, space: ob.StateSpace, scene: CollisionScene,
                 steps: np.ndarray, margin: float, budget: CheckBudget):
        super().__init__(si)
        self._space, self._scene, self._steps = space, scene, steps
        self._margin, self._budget, self._n = margin, budget, len(steps)

    def checkMotion(self, s1, s2) -> bool:  # noqa: N802 (OMPL's name)
        n = self._n
        a = np.array([s1[i] for i in range(n)])
        b = np.array([s2[i] for i in range(n)])
        count = max(1, int(self._space.validSegmentCount(s1, s2)))  # (OMPL's own count)
        states = a + np.outer(np.arange(1, count + 1) / count, b - a)
        states[-1] = b
        states *= self._steps
        if self._scene.moves_upright_items:
            # (most motions tip the item at their end, checked first: alone, cheaply)
            self._budget.states += 1
            if self._scene.first_collision(states[-1:], None, self._margin) is not None:
                return False
            states, count = states[:-1], count - 1
            if not count:
                return True
            order = bisection_order(count)
        else:
            order = [count - 1] + bisection_order(count - 1)
        first = self._scene.first_collision(states, order, self._margin)
        # (the budget counts the states OMPL's own validator would have checked)
        self._budget.states += count if first is None else first + 1
        return first is None


@dataclass(frozen=True)
class JointPath:
    """A checked polyline in joint space: vertices (k x n); `planned` if it is not the
    straight path (a detour through a learned waypoint, or OMPL's)."""

    names: tuple[str, ...]
    vertices: np.ndarray
    planned: bool
    checks: int = 0


def bisection_order(n: int) -> list[int]:
    """0..n-1 ordered so the middle comes first, then the quarters, ... (collisions in the
    middle of a motion are found after few checks)."""
    order, seen = [], set()
    queue = [(0, n - 1)]
    while queue:
        nxt = []
        for lo, hi in queue:
            if lo > hi:
                continue
            mid = (lo + hi) // 2
            if mid not in seen:
                seen.add(mid)
                order.append(mid)
            nxt += [(lo, mid - 1), (mid + 1, hi)]
        queue = nxt
    return order


class ArmMotionPlanner:
    """Plans joint-space paths for a set of joints in one `CollisionScene`."""

    def __init__(self, limits: JointLimits, options: ArmPlannerOptions | None = None):
        self.limits = limits
        self.options = options or ArmPlannerOptions()

    def states_free(self, scene: CollisionScene, states: np.ndarray) -> bool:
        """Every state free (exact checks in bisection order, stopping at the first
        collision)."""
        return scene.states_free(states, bisection_order(len(states)))

    def plan(self, scene: CollisionScene, start: Sequence[float], goal: Sequence[float],
             rng: np.random.Generator, sample: bool = True) -> JointPath | None:
        """A collision-free path from start to goal (joint order of the scene), or None.
        The start is where the robot is and is not checked; the goal is. Without `sample`
        only the straight path is tried."""
        names = tuple(scene.joints)
        start = np.asarray(start, dtype=float)
        goal = self.limits.unwrap_goal(names, start, np.asarray(goal, dtype=float))
        steps = self.limits.max_steps(names)
        before = scene.checks
        if not scene.is_free(goal):
            return None
        if self.options.try_straight:
            dense, _ = densify(np.vstack([start, goal]), steps)
            if self.states_free(scene, dense[1:-1]):
                return JointPath(names, np.vstack([start, goal]), False, scene.checks - before)
        if not sample:
            return None
        seed = int(rng.integers(1, 2**31 - 1))  # (drawn whether OMPL is asked or not)
        if self.options.waypoints:
            vertices = self._via_waypoint(scene, names, start, goal, steps)
            if vertices is not None:
                return JointPath(names, vertices, True, scene.checks - before)
        # First OMPL checks its motions coarsely and keeps a margin, so the densified
        # result (checked at every step) passes; if the start or goal lies within the
        # margin, or the result fails, it plans again checking every step, no margin. A
        # first search that spent its budget finding no path is not repeated finely: with
        # four times the checks per motion the same budget explores a quarter as far (over
        # c1-c3 none of those second searches found a path; each spent 1.6-1.7 s).
        upright = scene.moves_upright_items
        boxes = (self.options.upright_box, 0.0) if upright and self.options.upright_box \
            else (0.0,)
        drop, floors = self.options.upright_drop_m, scene.upright_floors
        if drop is not None and upright:
            scene.upright_floors = scene.upright_heights(np.vstack([start, goal])).min(
                axis=0) - drop
        try:
            for every, margin in ((self.options.check_every_steps, PLANNING_MARGIN_M),
                                  (1.0, 0.0)):
                if margin and not (scene.is_free(start, margin) and
                                   scene.is_free(goal, margin)):
                    continue
                for box in boxes:
                    vertices = self._ompl(scene, start, goal, steps, seed, every, margin, box)
                    if vertices is not None:
                        break
                if vertices is None:
                    if margin:
                        return None
                    continue
                dense, _ = densify(vertices, steps)
                if self.states_free(scene, dense[1:]):
                    return JointPath(names, vertices, True, scene.checks - before)
            return None
        finally:
            scene.upright_floors = floors

    def _via_waypoint(self, scene: CollisionScene, names: tuple[str, ...], start: np.ndarray,
                      goal: np.ndarray, steps: np.ndarray,
                      waypoints: Sequence[np.ndarray] | None = None) -> np.ndarray | None:
        """start, waypoint, goal: through the first of the arm's waypoints (or of
        `waypoints`) from which both legs are free, every state checked (None if none is,
        or the motion moves other joints than one arm's seven). A continuous joint's
        waypoint is taken at the turn that moves it least, start to goal."""
        if waypoints is None:
            waypoints = arm_waypoints().get(names)
        if not waypoints:
            return None
        limits = self.limits
        for waypoint in waypoints:
            via = waypoint.copy()
            within = True
            for i, name in enumerate(names):
                if name in limits.continuous:
                    turns = np.round((start[i] - via[i]) / (2 * math.pi)) + np.arange(-1, 2)
                    options = via[i] + 2 * math.pi * turns
                    costs = np.abs(options - start[i]) + np.abs(goal[i] - options)
                    via[i] = options[int(np.argmin(costs))]
                elif not limits.lower[name] <= via[i] <= limits.upper[name]:
                    within = False
            if not within or not scene.is_free(via):
                continue
            vertices = np.vstack([start, via, goal])
            dense, _ = densify(vertices, steps)
            if self.states_free(scene, dense[1:]):
                return vertices
        return None

    def _bounds(self, names: Sequence[str], start: np.ndarray, goal: np.ndarray,
                box: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Where OMPL samples each joint: within its limits (a continuous joint within a
        turn of either end), and with `box` only this far from the box the ends span."""
        lower, upper = [], []
        for i, name in enumerate(names):
            if name in self.limits.continuous:
                lo, hi = min(start[i], goal[i]) - math.pi, max(start[i], goal[i]) + math.pi
            else:
                lo, hi = self.limits.lower[name], self.limits.upper[name]
                lo, hi = min(lo, start[i], goal[i]), max(hi, start[i], goal[i])
            if box:
                lo = max(lo, min(start[i], goal[i]) - box)
                hi = min(hi, max(start[i], goal[i]) + box)
            lower.append(lo)
            upper.append(hi)
        return np.array(lower), np.array(upper)

    def _ompl(self, scene: CollisionScene, start: np.ndarray, goal: np.ndarray,
              steps: np.ndarray, seed: int, check_every: float,
              margin: float, box: float = 0.0) -> np.ndarray | None:
        n = len(start)
        lower, upper = self._bounds(scene.joints, start, goal, box)
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):  # normalised units: one unit = one allowed step of that joint
            bounds.setLow(i, float(lower[i] / steps[i]))
            bounds.setHigh(i, float(upper[i] / steps[i]))
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)

        def valid(state) -> bool:
            return scene.is_free([state[i] * steps[i] for i in range(n)], margin)

        budget = CheckBudget(valid, self.options.max_work, lambda: scene.narrow,
                             IDLE_ASKS if self.options.planner in IDLE_CHECKED_PLANNERS
                             else None)
        si.setStateValidityChecker(budget)
        si.setStateValidityCheckingResolution(check_every / space.getMaximumExtent())
        if self.options.planner in SEGMENT_PLANNERS:
            segments = _SegmentChecks(si, space, scene, steps, margin, budget)
            si.setMotionValidator(segments)
        si.setup()
        s, g = si.allocState(), si.allocState()
        for i in range(n):
            s[i] = float(start[i] / steps[i])
            g[i] = float(goal[i] / steps[i])
        pdef = ob.ProblemDefinition(si)
        pdef.setStartAndGoalStates(s, g)
        ou.setLogLevel(ou.LOG_NONE)  # failures are reported by the caller, not on stdout
        ou.RNG.setSeed(seed)  # see base_planner: the reseed takes effect
        planner = getattr(og, self.options.planner)(si)
        reach = (self.options.upright_range_steps if scene.moves_upright_items else 0.0) \
            or self.options.range_steps
        if reach:
            planner.setRange(reach)
        planner.setProblemDefinition(pdef)
        planner.setup()
        status = planner.solve(budget.condition())
        ou.setLogLevel(ou.LOG_WARN)
        if status.getStatus() != ob.PlannerStatus.EXACT_SOLUTION:
            return None
        path = pdef.getSolutionPath()
        if self.options.shorten:
            simplifier = og.PathSimplifier(si)
            simplifier.reduceVertices(path)
        # copy the floats out: the states are borrowed from objects that go away
        out = np.array([[st[i] * steps[i] for i in range(n)] for st in path.getStates()])
        out[0], out[-1] = start, goal
        return out
