"""Honest manipulation: grasps the PR2 gripper can make, a hollow bowl held by its rim,
upright items kept upright where a straight joint path would tip them (kinematic
backend: these are about planning, and run on every Python)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from cramlite.backends import load_backend
from cramlite.designators import (
    CostmapLocation,
    MoveTorsoAction,
    NavigateAction,
    ParkArmsAction,
    PickUpAction,
    simulated_robot,
)
from cramlite.designators.actions import grasps_of
from cramlite.designators.grasps import CLEARANCE_M, item_grasps
from cramlite.designators.motions import MoveArmJointsMotion
from cramlite.motion.arm_planner import ArmPlannerOptions
from cramlite.motion.ik import arm_ik
from cramlite.motion.trajectory import JointLimits, time_along_path
from cramlite.scene.gripper import gripper_geometry
from cramlite.scene.models import item_model
from cramlite.trace import read_trace
from cramlite.trace.check import checker_for
from cramlite.trace.physics import physics_findings
from cramlite.trial import TrialRunner
from cramlite.world import load_setup
from tests.conftest import ROOT, finite_difference_accelerations, run_cli

ITEMS = ROOT / "worlds" / "items"


def test_every_grasp_fits_the_open_gripper_and_the_cereal_is_taken_across_7_cm() -> None:
    fits = gripper_geometry().max_gap - 2 * CLEARANCE_M
    assert 0.080 < fits < 0.084  # (9.2 cm open, 5 mm to spare each side)
    for name in ("breakfast-cereal", "milk", "cup", "bowl", "spoon"):
        grasps = item_grasps(item_model(ITEMS / f"{name}.urdf", name))
        assert grasps and all(g.width_m <= fits for g in grasps), name
    cereal = item_grasps(item_model(ITEMS / "breakfast-cereal.urdf", "breakfast-cereal"))
    assert {round(g.width_m, 3) for g in cereal} == {0.07}  # never across its 19 cm
    assert {g.kind for g in item_grasps(item_model(ITEMS / "bowl.urdf", "bowl"))} == {"rim"}


def test_a_setup_with_an_item_the_gripper_cannot_hold_is_refused_naming_its_widths(
        tmp_path: Path) -> None:
    crate = (ITEMS / "milk.urdf").read_text().replace('"0.075 0.075 0.2"', '"0.15 0.12 0.2"')
    (tmp_path / "crate.urdf").write_text(crate.replace('name="milk"', 'name="crate"'))
    text = (ROOT / "worlds" / "setups" / "v1.yaml").read_text()
    text = text.replace("type: milk ", f"type: {tmp_path / 'crate.urdf'} ")
    assert str(tmp_path / "crate.urdf") in text
    setup = tmp_path / "crate.yaml"
    setup.write_text(text)
    done = run_cli("run", str(setup), "--backend", "kinematic")
    assert done.returncode == 2, done.stdout + done.stderr
    assert "Traceback" not in done.stderr
    message = done.stderr
    assert str(setup) in message and "items[2].type" in message, message
    assert "'milk'" in message and "15.0 x 12.0 cm" in message and "9.2 cm" in message


def test_the_hollow_bowl_is_taken_out_of_its_drawer_by_its_rim_and_carried(
        tmp_path: Path) -> None:
    path = tmp_path / "c1.jsonl"
    with TrialRunner("c1", backend="kinematic") as runner:
        result = runner.run("opm", seed=0, trace=path)
    assert result.success, result.failures
    assert result.items["bowl"]["ok"]
    trace = read_trace(path)
    checker = checker_for(trace)
    bowl = checker.items["bowl"]
    radius = max(bowl.extents[:2]) / 2
    held = [s for s in trace.states if "bowl" in s["held"]]
    assert len(held) > 50
    for state in held[:: max(1, len(held) // 40)]:
        arm = state["held"]["bowl"]
        tool = checker.robot_frames(state)[f"{arm[0]}_gripper_tool_frame"]
        x, y, z = state["objects"]["bowl"][:3]  # (its bottom's centre)
        across = math.dist(tool[:2, 3], (x, y))
        # the tool (between the fingertips) is at the wall, near the top: on the rim
        assert radius - 0.02 < across < radius + 0.01, across
        assert 0.01 < tool[2, 3] - z < bowl.extents[2], tool[2, 3] - z
    # and nothing of it was a magnet, a spill or a jump
    found = physics_findings(trace, checker)
    assert found == [], [f.describe() for f in found]


def test_a_rim_grasp_crosses_a_wall_of_the_bowl_near_its_middle_whatever_the_heading(
        ) -> None:
    """The bowl's rim is 16 flat walls: fingers closing where two meet press into the
    corner they form (2.1 mm at 9.8 degrees off a wall's middle, a user's setup found)."""
    from cramlite.designators.grasps import RIM_MAX_SQUINT_RAD

    (rim,) = [g for g in item_grasps(item_model(ROOT / "worlds" / "items" / "bowl.urdf",
                                                "bowl")) if g.kind == "rim"]
    assert rim.rim_sides == 16
    wall = 2 * math.pi / rim.rim_sides
    for item_yaw in (0.0, 0.3, -2.0):
        for heading in np.radians(np.arange(-180.0, 180.0, 0.5)):
            tool_yaw = rim.tool_yaw(item_yaw, float(heading))
            off = math.remainder(tool_yaw + math.pi / 2 - item_yaw - rim.rim_phase, wall)
            assert abs(off) <= RIM_MAX_SQUINT_RAD + 1e-9
            # turned no more than needed (none within 5 degrees of a middle)
            needed = max(0.0, abs(math.remainder(heading + math.pi / 2 - item_yaw
                                                 - rim.rim_phase, wall)) - RIM_MAX_SQUINT_RAD)
            assert abs(math.remainder(tool_yaw - heading, 2 * math.pi)) <= needed + 1e-9


def test_a_bowl_on_the_counter_is_held_by_its_rim_with_the_fingertips_outside_it(
        tmp_path: Path) -> None:
    setup = tmp_path / "bowl_on_counter.yaml"
    setup.write_text("""format: 1
name: bowl-on-counter
description: a user's setup whose bowl was gripped 2.1 mm deep where two walls meet
world: kitchen
robot:
  start: [-0.5, -1.8, 1.5708]
items:
  - {name: cup, type: cup, pose: [1.45, 0.6, 0.85, 0.0], surface: counter,
     category: none, target: [-0.9, 1.3, 0.86, 0.0]}
  - {name: bowl, type: bowl, pose: [1.45, -0.4, 0.85, 0.0], surface: counter,
     category: mid, target: [-0.95, 1.05, 0.86, 0.0]}
  - {name: spoon, type: spoon, pose: [1.4, -0.25, 0.6, 0.0], in: drawer_2,
     category: none, target: [-0.85, 1.55, 0.86, 0.0]}
baseline_order: [spoon, cup, bowl]
""")
    trace = tmp_path / "t.jsonl"
    done = run_cli("run", str(setup), "--backend", "kinematic", "--trace", str(trace))
    assert done.returncode == 0, done.stdout + done.stderr
    check = run_cli("replay", str(trace), "--check")
    assert check.returncode == 0 and "nothing found" in check.stdout, check.stdout


def _straight_tilt(check, a: np.ndarray, b: np.ndarray) -> float:
    return max((tilt for s in np.linspace(0, 1, 41) for _, tilt in check.tilts(a + s * (b - a))),
               default=0.0)


def _pick_up_the_milk(ctx) -> str:
    """Pick up v1's milk (upright) from the front; the arm that holds it."""
    ParkArmsAction().perform(ctx)
    MoveTorsoAction(0.25).perform(ctx)
    position, orientation = ctx.scene.object_pose("milk")
    location = CostmapLocation(position, grasps_of(ctx, "milk", ["front"]), "milk",
                               orientation=orientation)
    reach = next(iter(location.ground(ctx)))
    NavigateAction(reach.base).perform(ctx)
    PickUpAction("milk", reach=reach).perform(ctx)
    (arm,) = ctx.holding
    return arm


def test_a_tipped_state_is_found_from_the_tool_frames_as_from_every_link() -> None:
    """The tilt of an upright item is asked of the tool frames alone before every link is
    placed (most states OMPL samples for such a motion tip it): the same answer as from
    every link's frame, on states that tip it and states that do not."""
    setup = load_setup("v1")
    with load_backend("kinematic", setup) as backend, simulated_robot(backend) as ctx:
        names = arm_ik(_pick_up_the_milk(ctx)).joint_names
        check = ctx.collisions.check(names)
        assert check.moves_upright_items
        now = ctx.scene.joint_positions(names)
        start = np.array([now[n] for n in names])
        rng = np.random.default_rng(4)
        answers = []
        for scale in (0.05, 0.2, 0.6) * 40:
            q = start + rng.normal(0.0, scale, len(start))
            kept = check._kept_upright(check._link_frames(q[None]))
            assert check._tips(q) == (not kept)
            if not kept:
                assert not check.is_free(q) and check.first_collision(q[None]) == 0
            answers.append(kept)
        assert any(answers) and not all(answers)


def test_an_upright_item_stays_upright_where_the_straight_joint_path_would_tip_it(
        tmp_path: Path) -> None:
    setup = load_setup("v1")
    with load_backend("kinematic", setup) as backend, simulated_robot(backend) as ctx:
        trace = ctx.open_trace(tmp_path / "tip.jsonl", "v1", "set-table", "test", 0,
                               "kinematic")  # (picking it up and parking keep it upright too)
        arm = _pick_up_the_milk(ctx)
        ik = arm_ik(arm)
        names = ik.joint_names
        now = ctx.scene.joint_positions(names)
        start = np.array([now[n] for n in names])
        tool = ik.forward(now)
        aside = 0.15 if arm == "left" else -0.15
        target = pin.SE3(tool.rotation, tool.translation + np.array([0.05, aside, 0.05]))
        check = ctx.collisions.check(names)
        goal = None
        # an arm configuration for that tool pose the straight joint path to which would
        # tip the milk over (of all there are: the closed form lists them)
        found = ik._closed_form.solutions(target.rotation, target.translation,
                                          [now[names[0]]])
        for row in found[np.argsort(-np.abs(found - start).max(axis=1))]:
            q = ctx.limits.unwrap_goal(names, start, row)  # (as the motion will turn them)
            if check.is_free(q) and _straight_tilt(check, start, q) > 45:
                goal = dict(zip(names, row.tolist(), strict=True))
                break
        assert goal is not None
        t0 = ctx.drive_s + ctx.arm_s  # (the robot's clock before the motion)
        MoveArmJointsMotion(dict(goal)).perform(ctx)
        trace.close()
        reached = ik.forward(ctx.scene.joint_positions(names))
        assert np.linalg.norm(reached.translation - target.translation) < 0.005
    states = read_trace(tmp_path / "tip.jsonl").states
    assert len([s for s in states if s["t"] > t0]) > 50  # (the motion itself)
    for state in states:  # every executed state, read back from the trace
        qx, qy, qz, qw = state["objects"]["milk"][3:]
        up = 1 - 2 * (qx * qx + qy * qy)  # the milk's z axis, upwards component
        assert math.degrees(math.acos(max(-1.0, min(1.0, up)))) <= 15.0 + 1e-6, state["t"]


@pytest.mark.parametrize("seed", [1, 2])
def test_the_right_hand_puts_the_milk_in_the_cupboard_itself_when_clearing_up_c3(
        tmp_path: Path, seed: int) -> None:
    """OMPL's search for a motion that holds an upright item extends its trees by short
    steps (`ArmPlannerOptions.upright_range_steps`). With OMPL's default range, a fifth of
    the joint space's extent, most extensions tip the item somewhere along them: in this
    trial every search for a way into the cupboard spent its budget, and the right hand
    put the milk back for the left one to carry (34 s more of the robot's time).
    Short steps anywhere in the joint space wander, so the search keeps the milk at most
    `upright_drop_m` below the lower end of its motion: without that floor this trial
    swung it from the table (0.86 m) down to 0.48 m on its way to the shelf (1.0 m) in
    seed 1. The search first samples near the straight way (`upright_box`), then anywhere:
    without that first search the right hand gives the milk up in seed 2."""
    with TrialRunner("c3", backend="kinematic") as runner:
        result = runner.run("opm", "clear-table", seed=seed, trace=tmp_path / "c3.jsonl")
    assert result.success, result.failures
    gave_up = [line for line in result.log if "could not put" in line]
    assert gave_up == [], gave_up
    drop = ArmPlannerOptions().upright_drop_m
    states = read_trace(tmp_path / "c3.jsonl").states
    lowest = min(state["objects"]["milk"][2] for state in states)
    assert lowest >= 0.86 - drop - 0.005, lowest


@pytest.mark.parametrize("name", ["cup", "milk"])
def test_fingers_close_to_the_items_width_not_through_it(name: str) -> None:
    setup = load_setup("v1")
    with load_backend("kinematic", setup) as backend, simulated_robot(backend) as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        position, orientation = ctx.scene.object_pose(name)
        location = CostmapLocation(position, grasps_of(ctx, name), name,
                                   orientation=orientation)
        reach = next(iter(location.ground(ctx)))
        NavigateAction(reach.base).perform(ctx)
        PickUpAction(name, reach=reach).perform(ctx)
        (arm,) = ctx.holding
        finger = ctx.scene.joint_positions([f"{arm[0]}_gripper_l_finger_joint"])
        angle = next(iter(finger.values()))
        gap = gripper_geometry().gap_at(angle)
        # the fingertips stand the item's width apart (squeezed by at most 2 mm)
        assert reach.grasp.width_m - 0.002 <= gap <= reach.grasp.width_m + 0.001, gap


def test_the_hand_stays_on_the_handle_it_follows(tmp_path: Path) -> None:
    """Following a handle, the tool frame stays within 1 mm of the handle's grasp point in
    every state the drawer or door moves, and no fingertip goes more than 2 mm into the
    handle. (Before, the arm's straight joint-space way between two IK samples a 2 cm
    apart, each solved to 1 mm, strayed 1.8 mm from the door's arc: a fingertip 2.3 mm in
    the cupboard's handle, in this trial with failures injected.)"""
    from cramlite.designators.storage import _grasp_pose
    from cramlite.scene.scene import PlanningScene

    path = tmp_path / "c1.jsonl"
    with TrialRunner("c1", backend="kinematic") as runner:
        result = runner.run("baseline", seed=0, trace=path,
                            inject={"grasp": 0.3, "navigate": 0.3})
    assert result.success, result.failures
    trace = read_trace(path)
    checker = checker_for(trace)
    scene = PlanningScene(load_setup("c1"))
    world_joints = trace.header["world_joints"]
    by_joint = {c.joint: c for c in scene.containers.values()}
    offsets, previous = [], None
    for state in trace.states:
        if previous is not None and state["w"] != previous["w"]:
            moving = {world_joints[i] for i, (a, b) in enumerate(zip(
                state["w"], previous["w"], strict=True)) if a != b}
            (container,) = [by_joint[j] for j in moving]
            with scene.world_joint_at(container.joint, state["w"][world_joints.index(
                    container.joint)]):
                grasp = _grasp_pose(scene, container).translation
            robot = checker.robot_frames(state)
            offsets.append(min(math.dist(robot[f"{arm}_gripper_tool_frame"][:3, 3], grasp)
                               for arm in "lr"))
        previous = state
    assert len(offsets) > 300
    assert max(offsets) < 1e-3, max(offsets)
    grips = [f for f in physics_findings(trace, checker) if f.kind == "grip"]
    assert grips == [], [f.describe() for f in grips]


def test_a_segment_that_turns_the_joints_in_place_slows_only_around_itself() -> None:
    """A path timed along its tool's travel (a handle pulled, the tool moved straight):
    where the joints turn while the tool hardly moves (the arm changing its configuration
    at the end of an upright path), the tool slows down to take that segment at the
    joints' speed, the turning joint speeding up and slowing down at its acceleration,
    and the tool speeds up again after it; the rest of the path moves at the tool's
    speed. (Slowing the whole path for one such segment once stretched a placing of c3's
    milk to 270 s.)"""
    names = ("a", "b")
    limits = JointLimits({n: -10.0 for n in names}, {n: 10.0 for n in names},
                         {"a": 1.0, "b": 2.0}, {"a": 4.0, "b": 8.0}, frozenset(), frozenset())
    states = np.zeros((81, 2))
    states[1:, 0] = np.arange(1, 81) * 0.01  # joint a follows the tool, 1 cm a step
    states[41:, 1] = 0.5  # joint b turns 0.5 rad in one segment, the tool 1 um
    ds = np.array([1e-6 if k == 40 else 0.01 for k in range(80)])
    arc = np.concatenate([[0.0], np.cumsum(ds)])
    speed, accel = 0.2, 0.5
    timed = time_along_path(names, states, arc, limits, speed_m_s=speed, accel_m_s2=accel)
    dt = np.diff(timed.times)
    assert np.all(dt > 0)
    joint_speed = np.abs(np.diff(states, axis=0)) / dt[:, None]
    assert np.all(joint_speed <= np.array([1.0, 2.0]) * (1 + 1e-9))  # (the URDF's limits)
    mean = ds / dt  # (the tool's mean speed on each segment)
    assert np.all(mean <= speed * (1 + 1e-9))
    # the joints and the tool speed up and slow down at most at their accelerations, as
    # finite differences of the timed states measure it (from rest and to rest)
    found = finite_difference_accelerations(np.column_stack([states, arc]), timed.times)
    assert np.all(found <= np.array([4.0, 8.0, accel]) * (1 + 1e-9)), found.max(axis=0)
    assert dt[40] >= 0.5 / 2.0  # (b at most at its limit, the tool still)
    ramp = speed / accel  # (0.4 s to full speed, over 4 cm)
    cruising = [k for k in range(80) if ramp < timed.times[k] < timed.times[40] - 2 * ramp or
                timed.times[41] + 2 * ramp < timed.times[k] < timed.times[-1] - ramp - 0.05]
    assert len(cruising) > 40
    assert np.allclose(dt[cruising], 0.01 / speed)  # (the tool at full speed elsewhere)
    # two moves from rest to rest (0.79 m in all at 0.2 m/s, 0.4 s more each) and the
    # turn at b's speed limit (0.25 s), a little more where b speeds up and slows down
    least = arc[-1] / speed + 2 * ramp + 0.25
    assert least <= timed.times[-1] <= least + 0.3


def test_a_joint_turned_round_on_the_way_slows_the_path_around_it_only() -> None:
    """The tool moves on at full speed while a joint that was turning one way turns the
    other (an IK-projected line through a wrist's turn, as c3's upright park had it):
    that joint's speed cannot flip in an instant, so the path slows down around the turn,
    at the joints' and the tool's accelerations, and nowhere else."""
    names = ("a", "b")
    limits = JointLimits({n: -10.0 for n in names}, {n: 10.0 for n in names},
                         {"a": 3.0, "b": 3.0}, {"a": 12.0, "b": 12.0}, frozenset(),
                         frozenset())
    k = np.arange(121)
    states = np.column_stack([k * 0.005, np.where(k <= 60, k, 120 - k) * 0.04])
    arc = k * 0.01
    speed, accel = 0.25, 0.5
    timed = time_along_path(names, states, arc, limits, speed_m_s=speed, accel_m_s2=accel)
    found = finite_difference_accelerations(np.column_stack([states, arc]), timed.times)
    assert np.all(found <= np.array([12.0, 12.0, accel]) * (1 + 1e-9)), found.max(axis=0)
    dt = np.diff(timed.times)
    # b turns round at state 60 (1 rad/s one way, then the other, at full speed): it
    # passes there slowly and only the segments near it are slower than full speed
    full = 0.01 / speed
    assert dt[59] > 1.5 * full and dt[60] > 3 * full and dt[61] > 1.5 * full
    slowed = np.flatnonzero(dt > full * 1.001)
    ramp = speed ** 2 / (2 * accel)  # (from rest to full speed in 6.25 cm)
    ends = np.flatnonzero((arc[:-1] < ramp) | (arc[1:] > arc[-1] - ramp))
    assert set(slowed) - set(ends) <= set(range(50, 71)), sorted(set(slowed) - set(ends))
    # 1.2 m at 0.25 m/s from rest to rest (4.8 s and 0.5 s of ramps), and the turn: a few
    # tenths of a second (slowing the whole path for it would double its time)
    assert 5.3 < timed.times[-1] < 5.3 + 0.5
