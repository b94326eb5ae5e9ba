"""IK (Pinocchio) and base planning (OMPL) with the real libraries."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import numpy as np
import pinocchio as pin
import pytest

from cramlite.motion import BaseMotionPlanner, FootprintChecker, OccupancyMap, arm_ik
from cramlite.motion.ik import ArmIK
from cramlite.scene import PlanningScene
from cramlite.world import load_setup


@pytest.mark.parametrize("arm", ["right", "left"])
def test_ik_reaches_reachable_targets(arm: str) -> None:
    ik = arm_ik(arm)
    rng = np.random.default_rng(0)
    for _ in range(40):
        target = ik.forward(ik.from_q(ik.random_q(rng)))  # reachable by construction
        solution = ik.solve(target, rng)
        assert solution is not None
        reached = ik.forward(solution.joints)
        assert np.linalg.norm(reached.translation - target.translation) < 2e-3
        assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) < 2e-2
        model = ik.model
        q = ik.to_q(solution.joints)
        for i, lo, hi in ik._bounded:
            assert lo - 1e-9 <= q[i] <= hi + 1e-9  # joint limits respected
        del model


def test_ik_refuses_unreachable_targets() -> None:
    ik = arm_ik("right")
    rng = np.random.default_rng(1)
    far = pin.SE3(np.eye(3), np.array([1.6, -0.2, 0.9]))  # 1.6 m ahead: beyond the arm
    high = pin.SE3(np.eye(3), np.array([0.4, -0.2, 2.4]))  # above the robot's head
    assert ik.solve(far, rng) is None
    assert ik.solve(high, rng) is None


@pytest.mark.parametrize("arm", ["right", "left"])
def test_reach_test_never_refuses_a_reachable_target(arm: str) -> None:
    """The quick refusal (fingers and wrist against the shoulder's reach) says "out of
    reach" only where no descent would help: never for a pose the arm can take, at its own
    torso height or with the torso free."""
    ik = arm_ik(arm)
    rng = np.random.default_rng(7)
    torso = ik._torso[0]
    for _ in range(3000):
        q = ik.random_q(rng)
        target = ik.forward(ik.from_q(q))
        assert not ik.out_of_reach(target, fixed_torso_m=float(q[torso]))
        assert not ik.out_of_reach(target)


def test_the_reach_is_the_stretched_arm_and_sampled_where_the_neutral_arm_is_bent() -> None:
    """The PR2's arm at zero is stretched straight out: the farthest any configuration
    gets, taken without sampling. A model whose arm is bent at zero is sampled."""
    ik = ArmIK("right")  # (its own model: changed below)
    _, reach, _, wrist_reach = ik._reach_bounds()
    assert reach == pytest.approx(0.1 + 0.4 + 0.321 + 0.18 + 0.02, abs=1e-9)
    assert wrist_reach == pytest.approx(0.1 + 0.4 + 0.321 + 0.02, abs=1e-9)
    elbow = ik.model.getJointId("r_elbow_flex_joint")
    placement = ik.model.jointPlacements[elbow]
    ik.model.jointPlacements[elbow] = pin.SE3(pin.utils.rpyToMatrix(0.0, 0.0, math.pi / 2),
                                              placement.translation)  # forearm bent at zero
    shoulder = ik.model.getJointId("r_shoulder_pan_joint")
    pin.forwardKinematics(ik.model, ik.data, pin.neutral(ik.model))
    at_zero = np.linalg.norm(pin.updateFramePlacement(ik.model, ik.data, ik.frame_id).translation
                             - ik.data.oMi[shoulder].translation)
    _, bent_reach, _, _ = ik._reach_bounds()
    assert at_zero < 0.8 and bent_reach > at_zero + 0.02 + 0.05


def test_reach_test_refuses_a_gripper_facing_back_at_the_shoulder() -> None:
    """Fingers within reach, pointing back at the robot: the wrist would be 18 cm farther
    out than the fingers, beyond the arm; refused without a descent, and rightly."""
    ik = arm_ik("right")
    facing_back = pin.utils.rpyToMatrix(0.0, 0.0, math.pi)
    target = pin.SE3(facing_back, ik._shoulder + np.array([0.72, 0.0, 0.1]))
    assert np.linalg.norm(target.translation - ik._shoulder - [0, 0, 0.1]) < ik._reach
    assert ik.out_of_reach(target, fixed_torso_m=0.1)
    original = ik.out_of_reach
    try:  # and a descent from many starts finds nothing either
        ik.out_of_reach = lambda *args, **kwargs: False
        assert ik.solve(target, np.random.default_rng(0), fixed_torso_m=0.1,
                        restarts=20) is None
    finally:
        del ik.out_of_reach
    assert ik.out_of_reach == original

def test_ik_model_is_built_once_per_arm() -> None:
    assert arm_ik("right") is arm_ik("right")
    assert arm_ik("right").model.nq == 10  # torso + 7 arm joints, two continuous (cos, sin)


def test_torso_preference_keeps_the_torso_up() -> None:
    ik = arm_ik("right")
    target = pin.SE3(np.eye(3), np.array([0.6, -0.19, 0.95]))
    up = ik.solve(target, np.random.default_rng(0), preferred_torso_m=0.3)
    down = ik.solve(target, np.random.default_rng(0), preferred_torso_m=0.0)
    print(up.joints["torso_lift_joint"], down.joints["torso_lift_joint"])
    assert up.joints["torso_lift_joint"] > down.joints["torso_lift_joint"] + 0.1


@pytest.fixture(scope="module")
def planner():
    scene = PlanningScene(load_setup("v1"))
    checker = FootprintChecker(OccupancyMap(scene.environment_footprints()))
    yield BaseMotionPlanner(checker), checker


def test_ompl_plans_around_the_island(planner) -> None:
    base_planner, checker = planner
    # from south-east of the island to its west side: the straight line crosses it
    start, goal = (-0.3, 0.1, 0.0), (-1.95, 1.7, math.pi / 2)
    straight = base_planner._interpolate([start, goal])
    assert not all(checker.is_free(*p) for p in straight)
    path = base_planner.plan(start, goal, np.random.default_rng(0))
    assert path is not None
    assert all(checker.is_free(*p) for p in path.waypoints)
    assert path.waypoints[0][:2] == pytest.approx(start[:2])
    assert path.waypoints[-1][:2] == pytest.approx(goal[:2])
    gaps = [math.dist(a[:2], b[:2]) for a, b in zip(path.waypoints, path.waypoints[1:],
                                                     strict=False)]
    assert max(gaps) <= 0.051  # executed waypoint by waypoint
    assert path.length_m > math.dist(start[:2], goal[:2]) + 0.1
    print("path", round(path.length_m, 2), "m,", len(path.waypoints), "waypoints")


def test_ompl_is_reproducible_by_seed_and_reports_no_path(planner) -> None:
    base_planner, _ = planner
    start, goal = (-0.3, 0.1, 0.0), (-1.95, 1.7, math.pi / 2)
    a = base_planner.plan(start, goal, np.random.default_rng(5))
    base_planner.plan(start, goal, np.random.default_rng(9))  # planning in between
    b = base_planner.plan(start, goal, np.random.default_rng(5))
    assert a.waypoints == b.waypoints
    inside_counter = (1.5, 0.0, 0.0)
    assert base_planner.plan(start, inside_counter, np.random.default_rng(0)) is None


def test_a_slower_machine_plans_the_same_base_path(planner) -> None:
    """The base planner's search is bounded by its footprint checks, not by the clock:
    with every check 5 ms slower (a loaded machine), the same seed gives the same path."""
    import time

    from cramlite.motion import BaseMotionPlanner

    base_planner, checker = planner
    start, goal = (-0.3, 0.1, 0.0), (-1.95, 1.7, math.pi / 2)
    fast = base_planner.plan(start, goal, np.random.default_rng(3))

    class Slow:
        def __init__(self, inner):
            self.inner = inner
            self.occupancy = inner.occupancy

        def is_free(self, *pose):
            time.sleep(0.005)
            return self.inner.is_free(*pose)

        def all_free(self, poses):
            return all(self.is_free(*pose) for pose in poses)

    slow = BaseMotionPlanner(Slow(checker), base_planner.options)
    begin = time.perf_counter()
    again = slow.plan(start, goal, np.random.default_rng(3))
    spent = time.perf_counter() - begin
    print("slowed planning", round(spent, 2), "s")
    assert spent > 1.0  # (longer than the old budget of one second)
    assert again is not None and again.waypoints == fast.waypoints


def _search_in_child(code: str) -> subprocess.CompletedProcess:
    """Run a search's code in a child process (a search that hangs keeps it from
    answering: the test fails after a minute instead of hanging too)."""
    try:
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("the search did not end")
    assert done.returncode == 0, done.stderr
    return done


def test_a_base_search_between_poses_that_are_not_free_is_not_started() -> None:
    """Repairing a path plans again between its vertices, and rope shortcutting can put
    one where the base does not fit. OMPL waits for a valid goal for as long as its
    termination condition allows, and a budget of checks never ends while nothing is
    checked: a random setup's trial ran until the bench's timeout. Such a search is not
    started (in a child process without OMPL, which a hang would keep from answering)."""
    code = """
import math
import cramlite.motion.base_planner as base_planner
from cramlite.motion import BaseMotionPlanner, FootprintChecker, OccupancyMap
base_planner.ob = base_planner.og = None  # (OMPL asked: an AttributeError)
from cramlite.scene import PlanningScene
from cramlite.world import load_setup
scene = PlanningScene(load_setup("v1"))
checker = FootprintChecker(OccupancyMap(scene.environment_footprints()))
planner = BaseMotionPlanner(checker)
start, blocked, goal = (-0.3, 0.1, 0.0), (1.5, 0.0, 0.0), (-1.95, 1.7, math.pi / 2)
assert checker.is_free(*start) and checker.is_free(*goal) and not checker.is_free(*blocked)
resolution = planner.options.check_resolution
print(planner._repair([start, blocked, goal], 7, resolution),
      planner._repair([blocked, goal], 7, resolution))
"""
    done = _search_in_child(code)
    assert done.stdout.split() == ["None", "None"]


def test_a_search_that_does_no_work_ends() -> None:
    """A budget of work also ends a search that asks whether to stop again and again
    without checking anything: OMPL waiting for a valid goal (here one that is not free,
    with a budget that work alone would never spend). (In a child process, which a hang
    would keep from answering.)"""
    code = """
from ompl import base as ob, geometric as og, util as ou
from cramlite.motion.budget import IDLE_ASKS, CheckBudget
ou.setLogLevel(ou.LOG_NONE)
space = ob.RealVectorStateSpace(2)
bounds = ob.RealVectorBounds(2)
bounds.setLow(-1.0)
bounds.setHigh(1.0)
space.setBounds(bounds)
si = ob.SpaceInformation(space)
budget = CheckBudget(lambda state: state[0] < 0.5, 10**9,  # (the goal, x = 0.9: not free)
                     idle_asks=IDLE_ASKS)
si.setStateValidityChecker(budget)
si.setup()
start, goal = si.allocState(), si.allocState()
start[0], start[1], goal[0], goal[1] = -0.9, 0.0, 0.9, 0.0
problem = ob.ProblemDefinition(si)
problem.setStartAndGoalStates(start, goal)
planner = og.RRTConnect(si)
planner.setProblemDefinition(problem)
planner.setup()
status = planner.solve(budget.condition())
print(status.getStatus() == ob.PlannerStatus.EXACT_SOLUTION, budget.idle_asks == IDLE_ASKS)
"""
    done = _search_in_child(code)
    assert done.stdout.split()[-2:] == ["False", "True"]


def test_footprint_respects_yaw(planner) -> None:
    _, checker = planner
    # 3 cm from the island's near edge facing it: free; turned 45 degrees the corners hit
    assert checker.is_free(-0.30, 1.4, math.pi)
    assert not checker.is_free(-0.30, 1.4, math.pi * 0.75)


def test_footprint_check_agrees_with_every_point_looked_up(planner) -> None:
    """The base check skips the inside points nearer the base's middle than the clearance
    allows an obstacle; its answer is that of looking every point of the base up, at poses
    all over the kitchen and with a small obstacle (a 4 cm stool) that fits under the
    base."""
    _, checker = planner
    world_map = checker.occupancy
    boxes = [("stool", (0.9, 0.5, 0.0), (0.94, 0.54, 0.45))]
    floor = [("floor", (world_map.bounds.x_min, world_map.bounds.y_min, -0.01),
              (world_map.bounds.x_max, world_map.bounds.y_max, 0.0))]
    rng = np.random.default_rng(4)
    for occupancy in (world_map, OccupancyMap(floor + boxes)):
        check = FootprintChecker(occupancy)
        blocked = 0
        for _ in range(3000):
            x = rng.uniform(occupancy.bounds.x_min, occupancy.bounds.x_max)
            y = rng.uniform(occupancy.bounds.y_min, occupancy.bounds.y_max)
            if occupancy is not world_map:  # around the stool
                x, y = rng.uniform(0.5, 1.3), rng.uniform(0.1, 0.9)
            yaw = rng.uniform(-math.pi, math.pi)
            c, s = math.cos(yaw), math.sin(yaw)
            every = occupancy.blocked_at(check.outline @ np.array([[c, s], [-s, c]])
                                         + (x, y)).any()
            assert check.is_free(x, y, yaw) == (not every), (x, y, yaw)
            blocked += every
        assert 300 < blocked < 2700


@pytest.mark.parametrize("memory", [None, 50])
def test_footprints_checked_by_the_chunk_answer_as_one_pose_at_a_time(
        planner, memory, monkeypatch) -> None:
    """`all_free` (a path's waypoints, checked a chunk at a time in numpy) gives the answer
    of `is_free` asked pose by pose, and remembers what it would (also where the memory
    fills up and starts afresh within a path): with something sticking out of the base
    (an outline ahead of it, checked against the whole map and the boxes of items
    standing) and an exact check that decides where that outline touches. Poses must be
    finite; far ones are outside."""
    from cramlite.motion import footprint

    if memory is not None:
        monkeypatch.setattr(footprint, "KNOWN_POSES", memory)
    _, shared = planner
    ahead = np.array([[x, y] for x in np.linspace(0.36, 0.62, 8)
                      for y in np.linspace(-0.2, 0.2, 6)])
    asked: dict[str, list] = {"chunks": [], "alone": []}

    bounds = shared.occupancy.bounds
    corners = np.random.default_rng(5).uniform([bounds.x_min, bounds.y_min],
                                               [bounds.x_max, bounds.y_max], size=(8, 2))
    items = np.hstack([corners, corners + 0.12])  # (8 boxes of 12 cm, standing anywhere)

    def checker(log: list, boxes: np.ndarray = items) -> FootprintChecker:
        check = FootprintChecker(shared.occupancy)
        check.set_carried([(ahead, None, boxes)],
                          lambda x, y, yaw: log.append((x, y, yaw)) or math.sin(7 * x) > 0)
        return check

    chunks, alone = checker(asked["chunks"]), checker(asked["alone"])
    without = checker([], np.zeros((0, 4)))
    rng = np.random.default_rng(11)
    answers, before, differ = [], [], 0
    for _ in range(300):
        start = (rng.uniform(bounds.x_min, bounds.x_max),
                 rng.uniform(bounds.y_min, bounds.y_max), rng.uniform(-math.pi, math.pi))
        steps = rng.normal(0.0, [0.02, 0.02, 0.03], size=(int(rng.integers(1, 90)), 3))
        path = [tuple(p) for p in np.asarray(start) + np.cumsum(steps, axis=0)]
        if before and rng.uniform() < 0.4:  # (poses asked before, amid new ones)
            old = before[int(rng.integers(len(before)))]
            cut = int(rng.integers(len(path) + 1))
            path = path[:cut] + old[: int(rng.integers(1, len(old) + 1))] + path[cut:]
        before.append(path)
        expected = all(alone.is_free(*p) for p in path)
        differ += expected != all(without.is_free(*p) for p in path)
        assert chunks.all_free(path) == expected
        assert chunks._known == alone._known
        answers.append(expected)
    assert 30 < sum(answers) < 270  # (free paths and blocked ones)
    assert differ > 0  # (the items' boxes sent some poses to the exact check)
    for key, free in chunks._known.items():
        assert free == alone._is_free(*key[1:]), key
    # (the exact check was asked where the outline touched, and let some of them pass)
    touched = {tuple(round(v, 5) for v in pose) for pose in asked["chunks"]}
    assert touched
    assert any(free for key, free in chunks._known.items() if key[1:] in touched) or \
        memory is not None
    with pytest.raises(ValueError, match="finite"):
        chunks.all_free([(0.0, 0.0, 0.0), (math.nan, 0.0, 0.0)])
    far = [(1e18, -1e18, 0.0), (-1e300, 2.0, 1.0)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert chunks.all_free(far) is False and not any(alone.is_free(*p) for p in far)


def test_footprints_checked_by_the_chunk_remember_what_one_by_one_would(
        planner, monkeypatch) -> None:
    """Where checking the new poses of a path fills the memory (it starts afresh) before
    poses it knew from an earlier path, those are checked again and remembered, as one by
    one they would be."""
    from cramlite.motion import footprint

    monkeypatch.setattr(footprint, "KNOWN_POSES", 10)
    _, shared = planner
    probe, chunks, alone = (FootprintChecker(shared.occupancy) for _ in range(3))
    rng = np.random.default_rng(5)
    bounds = shared.occupancy.bounds
    free = []
    while len(free) < 13:
        pose = (round(rng.uniform(bounds.x_min, bounds.x_max), 5),
                round(rng.uniform(bounds.y_min, bounds.y_max), 5), 0.0)
        if probe._is_free(*pose):
            free.append(pose)
    earlier, later = free[:8], free[8:] + free[:8]
    for path in (earlier, later):
        assert chunks.all_free(path) and all(alone.is_free(*p) for p in path)
        assert chunks._known == alone._known


def test_a_door_swept_on_one_map_answers_as_each_of_its_positions_does() -> None:
    """The maps of c1's cupboard door at its stages of a swing, joined into one
    (`OccupancyMap.union`: what an access pose's footprint is checked against), answer
    every base pose as checking it on each map does, also where only a middle stage
    blocks it; maps of other bounds are not joined."""
    from cramlite.designators.context import occupancy_map
    from cramlite.designators.storage import FOOTPRINT_STAGES

    scene = PlanningScene(load_setup("c1"))
    maps = []
    for value in np.linspace(0.0, 2.3, FOOTPRINT_STAGES):
        scene.set_world_joint("cupboard_door_joint", float(value))
        maps.append(occupancy_map(scene))
    joined = OccupancyMap.union(maps)
    hinge = np.array(scene.link_bounds("cupboard_door")[0][:2])
    each = [FootprintChecker(m) for m in maps]
    union = FootprintChecker(joined)
    rng = np.random.default_rng(8)
    answers, only_middle = [], 0
    for _ in range(2500):
        x, y = hinge + rng.uniform(-1.2, 1.2, size=2)
        yaw = rng.uniform(-math.pi, math.pi)
        stages = [check.is_free(x, y, yaw) for check in each]
        assert union.is_free(x, y, yaw) == all(stages), (x, y, yaw, stages)
        answers.append(all(stages))
        only_middle += stages[0] and stages[-1] and not all(stages)
    assert 200 < sum(answers) < 2300 and only_middle > 20
    other = OccupancyMap([("floor", (-1.0, -1.0, -0.01), (1.0, 1.0, 0.0))])
    assert OccupancyMap.union([maps[0], other]) is None


def test_the_convex_hull_is_the_counter_clockwise_corners_of_the_points() -> None:
    """convex_hull_2d on mesh-like point clouds (many points inside, duplicates, points
    along the edges): its corners are input points, every point lies within it, each
    corner turns left (no point along an edge kept), it starts at the lowest x (then y);
    and unique_rows is np.unique's rows."""
    from cramlite.motion.footprint import convex_hull_2d, unique_rows

    rng = np.random.default_rng(3)
    for k in range(200):
        n = int(rng.integers(3, 400))
        points = np.round(rng.normal(size=(n, 2)) * rng.uniform(0.01, 0.5, size=2), 3)
        if k % 3 == 0:  # a box's outline: points along straight edges, and its corners
            t = rng.uniform(size=n)[:, None]
            corners = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.1], [0.0, 0.1]])
            edge = rng.integers(0, 4, size=n)
            points = np.vstack([corners, corners[edge] + t * (np.roll(corners, -1, 0)[edge]
                                                             - corners[edge])])
        points = np.vstack([points, points[: n // 4]])  # duplicates
        assert np.array_equal(unique_rows(points), np.unique(points, axis=0))
        hull = convex_hull_2d(points)
        assert all((points == corner).all(axis=1).any() for corner in hull)
        edges = np.roll(hull, -1, axis=0) - hull
        turn = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - \
            edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        assert (turn > 0).all()  # counter-clockwise, a strict corner at every point
        rel = points[:, None, :] - hull[None]
        cross = edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0]
        assert (cross >= -1e-12).all()  # every point within
        lowest = unique_rows(points)[0]
        assert np.array_equal(hull[0], lowest)
        if k % 3 == 0:
            assert len(hull) == 4


def test_seeded_descents_are_remembered_and_answer_as_a_fresh_solver_does() -> None:
    """A descent from a seeded start is kept for the process (trials of a setup ask the
    same ones again): the solutions (to the last bit) and the random numbers drawn are
    those of a solver that remembers nothing, for the same and for other targets (also
    one only turned), torso settings (free, preferred, fixed: from the same start) and
    seeds, and changing a returned solution does not change what is remembered."""
    from cramlite.motion.ik import ArmIK

    remembering, forgetting = ArmIK("right"), ArmIK("right")
    forgetting._descend_from_seed = forgetting._descend
    rng = np.random.default_rng(3)
    seeds = [{**remembering.from_q(remembering.random_q(rng)), "torso_lift_joint": 0.2}
             for _ in range(3)]
    targets = [remembering.forward(remembering.from_q(remembering.random_q(rng)))
               for _ in range(4)]
    turn = pin.exp3(np.array([0.0, 0.0, 0.3]))  # the same place, the hand turned
    targets += [pin.SE3(turn @ t.rotation, t.translation) for t in targets[:2]]
    settings = [{}, {"preferred_torso_m": 0.2}, {"fixed_torso_m": 0.2},
                {"fixed_torso_m": 0.1}]
    asks = [(target, seed, how) for target in targets for seed in seeds for how in settings]
    descents = []
    real_descend = remembering._descend
    remembering._descend = lambda *a, **k: descents.append(1) or real_descend(*a, **k)
    for rounds in range(2):
        rng_a, rng_b = np.random.default_rng(0), np.random.default_rng(0)
        solved = 0
        for target, seed, how in asks:
            got = remembering.solve(target, rng_a, seed, **how)
            want = forgetting.solve(target, rng_b, seed, **how)
            assert repr(got) == repr(want)  # (floats to the last bit, -0.0 too)
            if got is not None:
                solved += 1
                got.joints["r_elbow_flex_joint"] = 99.0  # (a caller's change stays its own)
        assert rng_a.random() == rng_b.random()  # the same numbers drawn
        assert solved > len(asks) // 2
        if rounds == 0:
            first = len(descents)
    again = len(descents) - first
    # the second round asks the same: its seeded descents came from memory, the random
    # restarts (as many as before) ran again
    assert 0 < again < first
