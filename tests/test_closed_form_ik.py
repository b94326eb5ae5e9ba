"""The PR2 arm's closed-form IK (cramlite.motion.closed_form_ik), checked against
Pinocchio's forward kinematics, and how `ArmIK.solve` uses it."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from cramlite.motion.closed_form_ik import PAN_STEP_RAD, ClosedFormArmIK, arm_geometry
from cramlite.motion.ik import ArmIK, IKOptions, arm_ik, arm_prefix
from cramlite.world.pr2 import TORSO_JOINT


def _solver(arm: str) -> tuple[ArmIK, ClosedFormArmIK]:
    ik = arm_ik(arm)
    geometry = arm_geometry(ik.model, arm_prefix(arm), ik.frame_id, TORSO_JOINT)
    assert geometry is not None
    return ik, ClosedFormArmIK(geometry)


def _joints(ik: ArmIK, row: np.ndarray) -> dict[str, float]:
    return {name: float(v) for name, v in zip(ik.joint_names, row, strict=True)}


@pytest.mark.parametrize("arm", ["right", "left"])
def test_every_closed_form_solution_puts_the_tool_at_the_pose_within_the_limits(
        arm: str) -> None:
    ik, solver = _solver(arm)
    rng = np.random.default_rng(11)
    rows = 0
    for _ in range(40):
        start = ik.from_q(ik.random_q(rng))
        target = ik.forward(start)
        found = solver.solutions(target.rotation, target.translation,
                                 [start[TORSO_JOINT]])
        rows += len(found)
        for row in found[::7]:  # (a sample of each pose's ~200: Pinocchio, one by one)
            reached = ik.forward(_joints(ik, row))
            assert np.linalg.norm(reached.translation - target.translation) < 1e-9
            assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) < 1e-9
        q = np.array([ik.to_q(_joints(ik, row)) for row in found]).reshape(-1, ik.model.nq)
        for i, lo, hi in ik._bounded:
            assert np.all(q[:, i] >= lo) and np.all(q[:, i] <= hi)
        assert np.all(found[:, 0] == start[TORSO_JOINT])  # the torso where it was asked
    assert rows > 40 * 50  # (a pose is reached in many ways: the pan is free)


@pytest.mark.parametrize("arm", ["right", "left"])
def test_the_closed_form_finds_the_configuration_a_pose_was_made_from(arm: str) -> None:
    """Completeness on the grid: a configuration away from the joint limits, from the
    straight elbow and wrist, and from the upper arm rolled a quarter turn (where the roll
    turns fast with the pan) has a solution next to it (its pan on the grid, every other
    joint within a small angle)."""
    ik, solver = _solver(arm)
    g = solver.geometry
    rng = np.random.default_rng(5)
    limits = [g.pan, g.lift, g.roll, g.elbow, g.flex]
    tried = 0
    while tried < 60:
        start = ik.from_q(ik.random_q(rng))
        row = np.array([start[n] for n in ik.joint_names])
        bounded = row[[1, 2, 3, 4, 6]]
        if any(v < lo + 0.1 or v > hi - 0.1 for v, (lo, hi) in zip(bounded, limits,
                                                                   strict=True)):
            continue
        if row[4] > -0.3 or row[6] > -0.3 or abs(math.cos(row[3])) < 0.3:
            continue
        tried += 1
        target = ik.forward(start)
        found = solver.solutions(target.rotation, target.translation, [row[0]])
        diff = found - row
        diff[:, [5, 7]] = (diff[:, [5, 7]] + math.pi) % (2 * math.pi) - math.pi
        nearest = np.abs(diff).max(axis=1).min()
        assert nearest < 0.05, (start, nearest)
        assert np.abs(found[:, 1] - row[1]).min() <= PAN_STEP_RAD / 2 + 1e-12


def test_poses_beyond_the_arm_have_no_closed_form_solution() -> None:
    ik, solver = _solver("right")
    far = pin.SE3(np.eye(3), np.array([1.6, -0.2, 0.9]))
    high = pin.SE3(np.eye(3), np.array([0.4, -0.2, 2.4]))
    facing_back = pin.SE3(pin.utils.rpyToMatrix(0.0, 0.0, math.pi),
                          ik._shoulder + np.array([0.72, 0.0, 0.2]))
    for target in (far, high, facing_back):
        assert len(solver.solutions(target.rotation, target.translation,
                                    np.linspace(0.0, 0.31, 32))) == 0


def test_a_model_not_shaped_as_a_pr2_arm_gets_no_closed_form() -> None:
    ik = arm_ik("right")
    assert arm_geometry(ik.model, "r", ik.frame_id, TORSO_JOINT) is not None
    model = pin.Model(ik.model)
    elbow = model.getJointId("r_elbow_flex_joint")
    model.jointPlacements[elbow] = pin.SE3(np.eye(3), np.array([0.4, 0.02, 0.0]))
    assert arm_geometry(model, "r", ik.frame_id, TORSO_JOINT) is None
    model = pin.Model(ik.model)
    wrist = model.getJointId("r_wrist_flex_joint")
    model.jointPlacements[wrist] = pin.SE3(pin.utils.rpyToMatrix(0.1, 0.0, 0.0),
                                           np.array([0.321, 0.0, 0.0]))
    assert arm_geometry(model, "r", ik.frame_id, TORSO_JOINT) is None
    assert arm_geometry(ik.model, "l", ik.frame_id, TORSO_JOINT) is None  # not that arm


def test_where_the_seeds_descent_fails_the_solution_nearest_the_seed_is_taken() -> None:
    """No random start: the closed-form configuration nearest the seed, the seed itself
    where it is one (its pan on the grid), and no random number drawn."""
    ik, solver = _solver("right")
    solving = ArmIK("right")
    solving._descend_from_seed = lambda *args, **kwargs: None  # (the seed's descent fails)
    rng = np.random.default_rng(2)
    checked = 0
    while checked < 15:
        row = np.array([ik.from_q(ik.random_q(rng))[n] for n in ik.joint_names])
        row[1] = solver.pans[np.abs(solver.pans - row[1]).argmin()]  # (on the grid)
        seed = _joints(ik, row)
        if not solving._clear_of_limits(seed):
            continue
        checked += 1
        target = ik.forward(seed)
        draws = np.random.default_rng(9)
        got = solving.solve(target, draws, seed, fixed_torso_m=seed[TORSO_JOINT])
        assert got is not None
        assert draws.bit_generator.state == np.random.default_rng(9).bit_generator.state
        for name, value in seed.items():
            assert math.isclose(math.remainder(got.joints[name] - value, 2 * math.pi), 0.0,
                                abs_tol=1e-6), name
        # turned a little: another configuration, still the nearest one there is
        turned = pin.SE3(pin.exp3(np.array([0.0, 0.05, 0.1])) @ target.rotation,
                         target.translation + np.array([0.01, -0.02, 0.0]))
        got = solving.solve(turned, draws, seed, fixed_torso_m=seed[TORSO_JOINT])
        found = solver.solutions(turned.rotation, turned.translation, [seed[TORSO_JOINT]])
        if got is None:
            assert len(found) == 0
            continue
        clear = solving._clear_rows(found)
        candidates = found[clear] if clear.any() else found
        distances = solving._distances(candidates, row)
        chosen = np.array([got.joints[n] for n in ik.joint_names])
        assert solving._distances(chosen[None], row)[0] <= distances.min() + 1e-9


def test_the_random_starts_remain_for_a_solver_without_the_closed_form() -> None:
    numeric = ArmIK("right", options=IKOptions(closed_form=False))
    assert numeric._closed_form is None
    rng = np.random.default_rng(4)
    for _ in range(10):
        target = numeric.forward(numeric.from_q(numeric.random_q(rng)))
        before = rng.bit_generator.state
        solution = numeric.solve(target, rng)
        assert solution is not None
        assert rng.bit_generator.state != before  # (its starts are drawn)
        reached = numeric.forward(solution.joints)
        assert np.linalg.norm(reached.translation - target.translation) < 2e-3


def test_remembered_solutions_answer_as_solving_afresh_does() -> None:
    """The closed form's solutions are kept per target and torso heights: the same
    solutions (to the last bit) for the same and for other targets and heights, and
    what is kept cannot be changed by whoever got it."""
    remembering, forgetting = ArmIK("right"), ArmIK("right")
    solver = forgetting._closed_form
    assert solver is not None
    forgetting._all_solutions = lambda target, torsos: solver.solutions(
        target.rotation, target.translation, np.asarray(torsos, dtype=float))
    rng = np.random.default_rng(8)
    targets = [remembering.forward(remembering.from_q(remembering.random_q(rng)))
               for _ in range(5)]
    turn = pin.exp3(np.array([0.0, 0.0, 0.2]))
    targets += [pin.SE3(turn @ t.rotation, t.translation) for t in targets[:2]]
    for _ in range(2):
        for target in targets:
            for heights in ([0.1], [0.2], [0.0, 0.31]):
                kept = remembering._all_solutions(target, heights)
                fresh = forgetting._all_solutions(target, heights)
                assert kept.tobytes() == fresh.tobytes() and kept.shape == fresh.shape
                if len(kept):
                    with pytest.raises(ValueError):
                        kept[0, 0] = 1.0
    assert len(remembering._solved) == len(targets) * 3


@pytest.mark.parametrize("arm", ["right", "left"])
def test_a_straight_wrist_and_an_elbow_at_the_edge_of_reach_are_solved(arm: str) -> None:
    """A wrist bent by nothing (its rolls add up; arccos alone cannot tell 1e-8 rad from
    0, and the rolls would follow rounding noise) and an elbow within 0.001-0.01 rad of
    straight (the pose at the edge of the arm's reach, which only pans near the one that
    turns the shoulder toward it reach): every row exact, and one found."""
    ik, solver = _solver(arm)
    rng = np.random.default_rng(21)
    for k in range(40):
        row = np.array([ik.from_q(ik.random_q(rng))[n] for n in ik.joint_names])
        row[1] = solver.pans[(k * 37) % len(solver.pans)]  # (the pan on the grid)
        row[6] = [0.0, -1e-12, -1e-10][k % 3]  # a straight wrist
        row[4] = min(row[4], -0.3)
        if k % 2:  # and an elbow at the edge of reach, the pan between two of the grid's
            row[4] = [-0.001, -0.005, -0.01][k % 3]
            row[6] = -0.5
            row[1] = min(row[1] + PAN_STEP_RAD / 2, solver.pans[-2])
        target = ik.forward(_joints(ik, row))
        found = solver.solutions(target.rotation, target.translation, [row[0]])
        assert len(found), row
        for each in found[::3]:
            reached = ik.forward(_joints(ik, each))
            assert np.linalg.norm(reached.translation - target.translation) < 1e-9
            assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) < 1e-9


def test_with_the_torso_free_the_nearest_height_that_reaches_is_taken() -> None:
    ik, solver = _solver("right")
    solving = ArmIK("right")
    solving._descend_from_seed = lambda *args, **kwargs: None  # (the seed's descent fails)
    grid = np.linspace(0.0, 0.31, 32)
    rng = np.random.default_rng(3)
    checked = 0
    while checked < 20:
        row = np.array([ik.from_q(ik.random_q(rng))[n] for n in ik.joint_names])
        target = ik.forward(_joints(ik, row))
        if len(solver.solutions(target.rotation, target.translation, [0.25])):
            continue  # (reached at the preferred height: that height)
        everywhere = solver.solutions(target.rotation, target.translation, grid)
        clear = solving._clear_rows(everywhere)
        if not clear.any():
            continue
        checked += 1
        got = solving.solve(target, rng, ik.from_q(ik.random_q(rng)), preferred_torso_m=0.25)
        assert got is not None
        nearest = np.abs(everywhere[clear, 0] - 0.25).min()
        assert abs(abs(got.joints[TORSO_JOINT] - 0.25) - nearest) < 1e-9


def test_a_fixed_torso_height_beyond_its_range_is_taken_as_its_limit() -> None:
    """As a descent clamps it: the closed form solves at the limit."""
    ik = arm_ik("right")
    solving = ArmIK("right")
    solving._descend_from_seed = lambda *args, **kwargs: None
    rng = np.random.default_rng(6)
    for height, limit in ((0.35, 0.31), (0.31 + 5e-17, 0.31), (-0.03, 0.0)):
        row = {**ik.from_q(ik.random_q(rng)), TORSO_JOINT: limit}
        got = solving.solve(ik.forward(row), rng, row, fixed_torso_m=height)
        assert got is not None and got.joints[TORSO_JOINT] == limit
