"""Parallel motion: the torso rises and the arms park while the base drives, as one
combined motion checked as one; a combination that collides is refused (the motions run
one after the other); the robot's time counts overlapping motions once."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cramlite.designators.context import ExecutionOptions
from cramlite.trace import read_trace
from cramlite.trial import TrialRunner
from tests.conftest import finite_difference_accelerations, run_cli

TORSO = "torso_lift_joint"


def _node(actions: list[dict], name: str) -> dict:
    return next(a for a in actions if a["name"] == name)


def _walk(nodes: list[dict]):
    for node in nodes:
        yield node
        yield from _walk(node["children"])


def test_the_torso_rises_while_the_base_drives_and_the_time_counts_once(tmp_path) -> None:
    trace = tmp_path / "v1.jsonl"
    with TrialRunner("v1", backend="kinematic") as runner:
        together = runner.run("opm", seed=0, trace=trace)
    with TrialRunner("v1", backend="kinematic",
                     options=ExecutionOptions(parallel_motion=False)) as runner:
        apart = runner.run("opm", seed=0)
    assert together.success and apart.success and together.order == apart.order
    assert apart.parallel_s == 0.0
    assert together.parallel_s > 5.0
    assert together.robot_time_s == pytest.approx(
        together.drive_s + together.arm_s - together.parallel_s, abs=1e-5)
    assert together.robot_time_s < apart.robot_time_s - 5.0
    # the task tree: the torso's action spans the first drive (they overlap)
    torso = _node(together.actions, "MoveTorsoAction")
    drive = next(n for n in _walk(together.actions) if n["name"] == "NavigateAction")
    assert torso["start_s"] == pytest.approx(drive["start_s"])
    assert torso["end_s"] - torso["start_s"] > 0.25 / 0.0131  # (its whole rise, 19 s)
    assert torso["end_s"] >= drive["end_s"] > torso["start_s"]  # (one combined motion)
    # the trace: states where both the base and the torso moved into them, marked so
    recorded = read_trace(trace)
    joints = recorded.header["joints"]
    both = 0
    for before, state in zip(recorded.states, recorded.states[1:], strict=False):
        if "parallel" not in state:
            continue
        assert "base" in state["parallel"]
        moved_base = not np.allclose(before["base"], state["base"])
        moved_torso = before["q"][joints.index(TORSO)] != state["q"][joints.index(TORSO)]
        both += moved_base and moved_torso
    assert both > 10
    # checked independently: nothing inside anything, accelerations within the limits
    checked = run_cli("replay", str(trace), "--check")
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "nothing found" in checked.stdout


def test_a_combined_motion_that_collides_is_refused_and_runs_one_after_the_other(
        tmp_path: Path) -> None:
    """The right arm reaching down and forward while the base drives up to the counter:
    the arm ends inside the counter in every combined motion, so none is sent; the arm
    moves first, alone (where it was planned), then the base drives."""
    from cramlite.backends import load_backend
    from cramlite.designators.context import RobotContext
    from cramlite.designators.motions import move_joints
    from cramlite.motion.base_timing import time_base_path
    from cramlite.motion.trajectory import BaseTrajectory
    from cramlite.scene.scene import PlanningScene
    from cramlite.world.setup import load_setup

    setup = load_setup("v1")
    with load_backend("recording", setup) as backend:
        scene = PlanningScene(setup)
        ctx = RobotContext(scene=scene, modules=backend.modules, rng=np.random.default_rng(0))
        from cramlite.world.pr2 import PARK_JOINTS

        move_joints(ctx, PARK_JOINTS["left"])  # (at the start, then put before the counter)
        move_joints(ctx, PARK_JOINTS["right"])
        move_joints(ctx, {TORSO: 0.25})
        backend.modules.execute_base_trajectory(BaseTrajectory(
            np.array([[0.0, 0.35, 0.0]]), np.zeros(1)))
        ctx.observe()
        reach = {"r_shoulder_pan_joint": 0.0, "r_shoulder_lift_joint": 0.5,
                 "r_upper_arm_roll_joint": 0.0, "r_elbow_flex_joint": -0.15,
                 "r_forearm_roll_joint": 0.0, "r_wrist_flex_joint": -0.1,
                 "r_wrist_roll_joint": 0.0}
        move_joints(ctx, reach, while_driving=True)
        assert len(ctx.deferred) == 1 and ctx.scene.joint_positions(["r_shoulder_lift_joint"])[
            "r_shoulder_lift_joint"] == pytest.approx(0.5)  # (believed: planning goes on)
        timed = time_base_path([(0.0, 0.35, 0.0), (0.85, 0.35, 0.0)])
        sent_before = len(backend.sent)
        ctx.drive(BaseTrajectory(timed.poses, timed.times))
        commands = [c["command"] for c in backend.sent[sent_before:]]
        assert commands == ["joint_trajectory", "base_trajectory"]  # one after the other
        assert ctx.overlap_s == 0.0 and not ctx.deferred
        assert any("not moved while driving" in line for line in ctx.log)
        # the same arm motion with a drive away from the counter: sent as one
        backend.modules.execute_base_trajectory(BaseTrajectory(
            np.array([[0.0, 0.35, 0.0]]), np.zeros(1)))
        ctx.observe()
        move_joints(ctx, PARK_JOINTS["right"])
        move_joints(ctx, reach, while_driving=True)
        back = time_base_path([(0.0, 0.35, 0.0), (-0.3, 0.35, 0.0)])
        sent_before = len(backend.sent)
        ctx.drive(BaseTrajectory(back.poses, back.times))
        commands = [c["command"] for c in backend.sent[sent_before:]]
        assert commands == ["parallel_trajectory"] and ctx.overlap_s > 0.5
        sent = backend.sent[-1]
        assert json.dumps(sent)  # (what a driver would be sent: plain JSON)
        assert len(sent["times"]) == len(sent["poses"]) == len(sent["positions"])


@pytest.mark.parametrize("together", [True, False])
def test_parallel_of_the_torso_and_a_drive_takes_the_longer_ones_time(together: bool) -> None:
    from cramlite.designators import (
        MoveTorsoAction,
        NavigateAction,
        Parallel,
        ParkArmsAction,
        simulated_robot,
    )
    from cramlite.world.setup import load_setup

    options = ExecutionOptions(parallel_motion=together)
    with simulated_robot(load_setup("v1"), backend="kinematic", options=options) as ctx:
        ParkArmsAction().perform(ctx)
        t0, drive0, arm0 = ctx.time_s, ctx.drive_s, ctx.arm_s
        Parallel([MoveTorsoAction(0.25), NavigateAction((-0.5, -0.8, math.pi / 2))]).perform(ctx)
        torso, drive = ctx.arm_s - arm0, ctx.drive_s - drive0
        assert torso > 15.0 and drive > 0.5  # (the torso rises 25 cm at 1.3 cm/s)
        assert ctx.modules.joint_positions([TORSO])[TORSO] == pytest.approx(0.25)
        assert ctx.modules.base_pose()[1] == pytest.approx(-0.8, abs=0.05)
        took = ctx.time_s - t0
        assert took == pytest.approx(max(torso, drive) if together else torso + drive, abs=1e-6)


@pytest.mark.parametrize("backend", ["kinematic", "pybullet"])
def test_a_parallel_motion_nobody_watches_goes_straight_to_its_last_state(backend) -> None:
    """A simulator that moves the robot kinematically puts the world in each state of a
    combined drive and joint motion only while something watches (a trace): else it goes
    to the last state (stepping 2 655 states a v1 trial cost pybullet 0.11 s), ending
    where stepping ends."""
    from cramlite.backends import load_backend, runnable_backends
    from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
    from cramlite.world import load_setup

    if backend not in runnable_backends():
        pytest.skip(f"{backend} is not installed")
    times = np.linspace(0.0, 2.0, 101)
    base = BaseTrajectory(np.column_stack([np.linspace(-0.5, 0.5, 101), np.full(101, -1.8),
                                           np.linspace(0.0, 0.3, 101)]), times)
    joints = JointTrajectory((TORSO,), np.linspace(0.05, 0.2, 101)[:, None], times)
    ends = []
    for watched in (False, True):
        with load_backend(backend, load_setup("v1")) as world:
            modules = world.modules
            calls = []
            for name in ("execute_base_trajectory", "execute_joint_trajectory"):
                method = getattr(modules, name)

                def spy(trajectory, on_state=None, method=method, name=name, calls=calls):
                    calls.append(name)
                    return method(trajectory, on_state)

                setattr(modules, name, spy)
            seen = []
            modules.execute_parallel(base, joints, seen.append if watched else None)
            ends.append((modules.base_pose(), modules.joint_positions([TORSO])[TORSO]))
            if watched:
                assert seen == list(range(101)) and len(calls) == 2 * 101
            else:
                assert seen == [] and len(calls) == 2  # (each primitive sent whole)
    for (pose, torso) in ends:
        assert pose == pytest.approx((0.5, -1.8, 0.3)) and torso == pytest.approx(0.2)


def test_a_joint_motion_sampled_at_a_drives_times_stays_on_its_profile() -> None:
    """A deferred joint motion runs at the drive's times (its states are farther apart):
    sampled on its own Ruckig profile there, its speed changes at most at each joint's
    acceleration however finely it is sampled, and at its own times it is at its own
    states (interpolated straight between them, the speed would jump at every state)."""
    from cramlite.designators.context import _combined
    from cramlite.motion.trajectory import BaseTrajectory, JointLimits, time_joint_path

    names = ("torso_lift_joint", "r_shoulder_pan_joint")
    limits = JointLimits({n: -3.0 for n in names}, {n: 3.0 for n in names},
                         {names[0]: 0.013, names[1]: 2.088},
                         {names[0]: 0.052, names[1]: 8.352}, frozenset(),
                         frozenset({names[0]}))
    joints = time_joint_path(names, np.array([[0.0, 0.0], [0.1, -1.0], [0.25, 0.5]]), limits)
    assert np.allclose(joints.at_times(joints.times), joints.positions, atol=1e-9)
    times = np.arange(0.0, 10.0, 0.02)
    drive = BaseTrajectory(np.column_stack([times * 0.1, np.zeros_like(times),
                                            np.zeros_like(times)]), times)
    _, combined, _ = _combined(drive, joints, 1.0)
    assert np.diff(combined.times).min() < 0.03  # (sampled at the drive's 20 ms during it)
    a = finite_difference_accelerations(combined.positions, combined.times)
    assert np.all(a <= np.array([0.052, 8.352]) * (1 + 1e-6) + 1e-9), a.max(axis=0)
    assert np.allclose(combined.positions[-1], joints.positions[-1])
