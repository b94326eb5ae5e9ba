"""Arm motions through learned waypoints: tried before OMPL, taken only where both legs are
free at every step, continuous joints turned the least; the shipped waypoints well formed
and used by the shipped setups (kinematic backend: these run without pybullet too)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cramlite.designators import simulated_robot
from cramlite.motion import arm_planner
from cramlite.motion.arm_planner import WAYPOINTS_FILE, ArmMotionPlanner
from cramlite.motion.ik import arm_joint_names
from cramlite.motion.trajectory import densify
from cramlite.trial import TrialRunner
from cramlite.world import load_setup

RIGHT_ARM = tuple(arm_joint_names("right"))
#: Facing the island from 42 cm: the hand below the edge, and above the top behind it
#: (their straight path goes 7.7 cm deep through the island).
BELOW_EDGE = np.array((-1.263, 0.984, -2.406, -2.07, 1.964, -1.249, -1.611))
OVER_TOP = np.array((-0.557, 0.556, -1.045, -1.956, 3.011, -1.202, -2.261))
BESIDE_ISLAND = (-0.25, 1.3, math.pi)
#: A free arm pose from which both legs are free (a vertex of an OMPL detour), and a free
#: one from which a leg goes through the island.
GOOD = np.array((-1.142, 0.225, -2.269, -2.092, 1.195, -1.482, -1.548))
BAD = np.array((-0.964, 1.14, -0.801, -1.927, 0.605, -1.649, -0.545))


class CountsSearches(ArmMotionPlanner):
    """Counts the OMPL searches it makes."""

    searches = 0

    def _ompl(self, *args):
        self.searches += 1
        return super()._ompl(*args)


@pytest.fixture
def beside_island():
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        scene = ctx.collisions.check(list(RIGHT_ARM), base=BESIDE_ISLAND,
                                     fixed={"torso_lift_joint": 0.25})
        yield ctx, scene


def test_a_motion_goes_through_the_first_waypoint_whose_legs_are_free(beside_island,
                                                                       monkeypatch) -> None:
    ctx, scene = beside_island
    steps = ctx.limits.max_steps(RIGHT_ARM)
    straight, _ = densify(np.vstack([BELOW_EDGE, OVER_TOP]), steps)
    assert not scene.states_free(straight)
    assert scene.is_free(BAD) and scene.is_free(GOOD)
    # the good waypoint given some turns away on its continuous joints
    turned = GOOD.copy()
    continuous = [i for i, n in enumerate(RIGHT_ARM) if n in ctx.limits.continuous]
    assert continuous  # (the forearm's and the wrist's roll)
    turned[continuous] += 4 * math.pi
    monkeypatch.setattr(arm_planner, "arm_waypoints", lambda: {RIGHT_ARM: (BAD, turned)})
    planner = CountsSearches(ctx.limits)
    path = planner.plan(scene, BELOW_EDGE, OVER_TOP, np.random.default_rng(0))
    assert path is not None and path.planned
    assert planner.searches == 0  # (no OMPL)
    assert len(path.vertices) == 3
    assert path.vertices[0] == pytest.approx(BELOW_EDGE)
    assert path.vertices[2] == pytest.approx(OVER_TOP)
    via = path.vertices[1]
    fixed = [i for i in range(len(RIGHT_ARM)) if i not in continuous]
    assert via[fixed] == pytest.approx(GOOD[fixed])  # the good one, not the bad one
    for i in continuous:  # the same angle, at the turn that moves the joint least
        assert math.remainder(via[i] - GOOD[i], 2 * math.pi) == pytest.approx(0, abs=1e-9)
        moved = abs(via[i] - BELOW_EDGE[i]) + abs(OVER_TOP[i] - via[i])
        assert all(moved <= abs(v - BELOW_EDGE[i]) + abs(OVER_TOP[i] - v) + 1e-9
                   for v in via[i] + 2 * math.pi * np.arange(-3, 4))
    dense, _ = densify(path.vertices, steps)
    assert np.abs(np.diff(dense, axis=0)).max() <= steps.max() + 1e-9
    assert all(not scene.contacts(q) for q in dense)  # every executed state free


def test_with_no_waypoint_free_ompl_plans_and_without_waypoints_too(beside_island,
                                                                      monkeypatch) -> None:
    ctx, scene = beside_island
    monkeypatch.setattr(arm_planner, "arm_waypoints", lambda: {RIGHT_ARM: (BAD,)})
    planner = CountsSearches(ctx.limits)
    path = planner.plan(scene, BELOW_EDGE, OVER_TOP, np.random.default_rng(0))
    assert path is not None and planner.searches >= 1
    monkeypatch.setattr(arm_planner, "arm_waypoints", lambda: {RIGHT_ARM: (GOOD,)})
    off = CountsSearches(ctx.limits, arm_planner.ArmPlannerOptions(waypoints=False))
    assert off.plan(scene, BELOW_EDGE, OVER_TOP, np.random.default_rng(0)) is not None
    assert off.searches >= 1
    # (the seed is drawn either way: what follows a motion does not depend on how it
    # was planned)
    a, b = np.random.default_rng(3), np.random.default_rng(3)
    CountsSearches(ctx.limits).plan(scene, BELOW_EDGE, OVER_TOP, a)
    off.plan(scene, BELOW_EDGE, OVER_TOP, b)
    assert a.integers(1 << 30) == b.integers(1 << 30)


def test_the_shipped_waypoints_are_arm_poses_within_the_limits() -> None:
    data = json.loads(WAYPOINTS_FILE.read_text(encoding="utf-8"))
    assert set(data["learned_from"]) >= {"setups", "seeds", "strategies"}
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        limits = ctx.limits
    shipped = arm_planner.arm_waypoints()
    assert set(shipped) == {RIGHT_ARM, tuple(arm_joint_names("left"))}
    for names, waypoints in shipped.items():
        assert waypoints
        for w in waypoints:
            assert len(w) == 7
            for name, value in zip(names, w, strict=True):
                if name not in limits.continuous:
                    assert limits.lower[name] <= value <= limits.upper[name], (name, value)


def test_the_shipped_waypoints_spare_c1_most_of_its_ompl_searches(monkeypatch) -> None:
    """c1 closes its cupboard door reaching round it: OMPL's detours, most of them found
    through a shipped waypoint instead; the same order either way."""
    searches = []
    search = ArmMotionPlanner._ompl

    def counted(self, *args):
        searches.append(1)
        return search(self, *args)

    monkeypatch.setattr(ArmMotionPlanner, "_ompl", counted)
    with TrialRunner("c1", backend="kinematic") as runner:
        report = runner.run("opm", seed=0)
        through_waypoints = len(searches)
        searches.clear()
        monkeypatch.setattr(arm_planner, "arm_waypoints", lambda: {})
        without = runner.run("opm", seed=0)
    print("OMPL searches with the waypoints", through_waypoints, "without", len(searches))
    assert report.success and without.success
    assert report.order == without.order == ["bowl", "milk", "breakfast-cereal", "cup",
                                             "spoon"]
    assert len(searches) >= 4 and through_waypoints <= len(searches) // 2
