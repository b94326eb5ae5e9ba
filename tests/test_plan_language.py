"""The plan language on real designators (kinematic backend): every construct in the task
tree; Monitor brakes a motion within the limits at the state its condition fires;
Retry recovers on what the world reports; an action's validate() always runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cramlite.backends import load_backend
from cramlite.designators import (
    Code,
    Monitor,
    MonitorFired,
    MoveTorsoAction,
    NavigateAction,
    Parallel,
    ParkArmsAction,
    PlacementFailed,
    PlanFailure,
    Repeat,
    Retry,
    TransportAction,
    TryAll,
    TryInOrder,
    simulated_robot,
)
from cramlite.designators.tasks import ActionDesignator
from cramlite.trace import read_trace
from cramlite.trace.physics import physics_findings
from cramlite.world import load_setup


@pytest.fixture
def robot():
    with load_backend("kinematic", load_setup("v1")) as backend, \
            simulated_robot(backend) as ctx:
        yield ctx


def _fails(reason: str):
    def step(ctx):
        raise PlanFailure(reason)
    return step


def _node(ctx, name: str) -> dict:
    return next(n for n in ctx.tasks.as_list() if n["name"] == name)


def test_try_all_runs_every_step_and_succeeds_if_one_did(robot) -> None:
    ran = []
    assert TryAll([_fails("a"), lambda ctx: ran.append("b") or "b", _fails("c")]).perform(
        robot) == [None, "b", None]
    assert ran == ["b"]
    assert _node(robot, "TryAll")["status"] == "succeeded"
    with pytest.raises(PlanFailure, match="tried") as caught:
        TryAll([_fails("x"), _fails("y")], describe=lambda s: "step").perform(robot)
    assert len(caught.value.tried) == 2


def test_repeat_and_code_are_nodes_with_their_spans(robot) -> None:
    counter = []
    Repeat(Code(lambda ctx: counter.append(ctx.time_s), name="count"), 3).perform(robot)
    assert len(counter) == 3
    node = _node(robot, "Repeat")
    assert [c["name"] for c in node["children"]] == ["Code(count)"] * 3
    with pytest.raises(PlanFailure):
        Repeat(_fails("stop"), 2).perform(robot)


def test_retry_recovers_and_plans_on_what_the_world_reports(robot) -> None:
    """The first try leaves a poisoned belief (the cup believed 40 cm off) and fails; the
    recovery runs, the scene observes the world again, and the second try sees the cup
    where it is."""
    true_cup = robot.scene.object_pose("cup")
    seen, recovered = [], []

    def attempt(ctx):
        seen.append(ctx.scene.object_pose("cup")[0])
        if len(seen) == 1:
            (x, y, z), q = ctx.scene.object_pose("cup")
            ctx.scene.belief.poses["cup"] = ((x + 0.4, y, z), q)  # poisoned
            raise PlanFailure("dropped it")
        return "done"

    assert Retry(attempt, 3, lambda ctx, failure: recovered.append(str(failure))).perform(
        robot) == "done"
    assert recovered == ["dropped it"]
    assert np.allclose(seen[1], true_cup[0])
    with pytest.raises(PlanFailure, match="attempt 1.*attempt 2"):
        Retry(_fails("never"), 2).perform(robot)


def test_parallel_of_two_transports_runs_both_and_reports_a_failure_after_all(robot) -> None:
    setup = load_setup("v1")
    cup, milk = setup.item("cup"), setup.item("milk")
    ParkArmsAction().perform(robot)
    MoveTorsoAction(0.25).perform(robot)
    ended = Parallel([TransportAction("cup", target=cup.target.xyz,
                                      target_yaw=cup.target.yaw),
                      TransportAction("milk", target=milk.target.xyz,
                                      target_yaw=milk.target.yaw)]).perform(robot)
    for spec, where in zip((cup, milk), ended, strict=True):
        assert math.dist(robot.scene.object_pose(spec.name)[0][:2], spec.target.xyz[:2]) < 0.05
        assert where == robot.scene.object_pose(spec.name)[0]  # (perform says where)
    assert len(repr(robot)) < 300 and "'v1'" in repr(robot)  # (no path dump)
    node = _node(robot, "Parallel")
    assert [c["name"] for c in node["children"]] == ["TransportAction"] * 2
    ran = []
    with pytest.raises(PlanFailure, match="first"):
        Parallel([_fails("first"), lambda ctx: ran.append(1)]).perform(robot)
    assert ran == [1]  # (the other branch ran although the first failed)


def _speeds_and_accels(states: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    t = np.array([s["t"] for s in states])
    xy = np.array([s["base"][:2] for s in states])
    v = np.linalg.norm(np.diff(xy, axis=0), axis=1) / np.maximum(np.diff(t), 1e-9)
    return t, v


def test_a_monitor_brakes_the_base_where_its_condition_fires(robot, tmp_path) -> None:
    path = tmp_path / "monitor.jsonl"
    robot.open_trace(path, "v1", "test", "none", 0, "kinematic")
    ParkArmsAction().perform(robot)
    start = robot.time_s
    fire_at = start + 1.0  # (the drive to the counter takes longer)
    with pytest.raises(MonitorFired, match="fired at t = "):
        Monitor(lambda state: state.t >= fire_at,
                NavigateAction((0.8, 0.0, 0.0)), name="too slow").perform(robot)
    end_base = robot.scene.base
    assert math.dist(end_base[:2], (0.8, 0.0)) > 0.5  # stopped on the way
    ParkArmsAction("left").perform(robot)  # (the plan goes on; the trace too)
    robot.trace.close()
    trace = read_trace(path)
    states = trace.states
    t, v = _speeds_and_accels(states)
    moving = np.flatnonzero(v > 1e-6)
    assert len(moving) and t[moving[-1] + 1] > fire_at  # it braked after the firing
    assert t[moving[-1] + 1] - fire_at < 2.0  # and came to rest soon after it
    fired_speed = np.interp(fire_at, t[1:], v)
    assert fired_speed > 0.3  # (it was driving when the condition fired)
    # braking within the base's limits: the independent trace check finds nothing
    found = [f for f in physics_findings(trace) if f.kind == "base acceleration"]
    assert found == [], [f.describe() for f in found]
    assert _node(robot, "Monitor")["status"] == "failed"


@pytest.mark.parametrize("after_s", [0.2, 0.3, 0.5, 0.7])
def test_a_monitor_that_fires_early_in_a_turning_drive_stops_it_short(robot, tmp_path,
                                                                      after_s) -> None:
    """(A red-team pass: fired 0.5 s into the drive to the origin, which turns as it
    goes, the braking never fitted the limits, so the drive ran on to its goal while
    the message said it braked.) The braking keeps the path's own states: it fits."""
    path = tmp_path / "early.jsonl"
    robot.open_trace(path, "v1", "test", "none", 0, "kinematic")
    ParkArmsAction().perform(robot)
    start = robot.time_s
    with pytest.raises(MonitorFired, match="braked to rest"):
        Monitor(lambda state: state.t > start + after_s,
                NavigateAction((0.0, 0.0, 0.0))).perform(robot)
    assert math.dist(robot.scene.base[:2], (0.0, 0.0)) > 0.5  # stopped on the way
    assert robot.time_s - start < 2.5  # (the whole drive takes 2.9 s)
    robot.trace.close()
    found = [f for f in physics_findings(read_trace(path))
             if f.kind in ("base acceleration", "yaw acceleration")]
    assert found == [], [f.describe() for f in found]


def test_an_arm_motion_braked_at_any_time_stays_within_the_joint_limits(robot,
                                                                       tmp_path) -> None:
    """Braking checked its last step to rest over the whole step, the trace check over
    half of it: braked on the path's own states (far apart as it slows), an elbow reached
    14.3 rad/s^2 of its 13.2."""
    from cramlite.designators import MoveArmJointsMotion

    out = {"r_shoulder_pan_joint": -1.0, "r_shoulder_lift_joint": 0.3,
           "r_elbow_flex_joint": -0.5, "l_shoulder_pan_joint": 1.0,
           "l_shoulder_lift_joint": 0.3, "l_elbow_flex_joint": -0.5}
    path = tmp_path / "arms.jsonl"
    robot.open_trace(path, "v1", "test", "none", 0, "kinematic")
    ParkArmsAction().perform(robot)
    fired = 0
    for after_s in (0.0, 0.05, 0.3, 0.8):
        MoveArmJointsMotion(out).perform(robot)
        start = robot.time_s
        try:
            Monitor(lambda state, start=start, after_s=after_s: state.t > start + after_s,
                    ParkArmsAction()).perform(robot)
        except MonitorFired:
            fired += 1
    robot.trace.close()
    assert fired == 4
    found = [f for f in physics_findings(read_trace(path)) if "acceleration" in f.kind]
    assert found == [], [f.describe() for f in found]


def test_a_monitor_that_fires_as_a_motion_ends_says_it_ran_to_its_end(robot) -> None:
    ParkArmsAction().perform(robot)
    start = robot.time_s
    with pytest.raises(MonitorFired, match="near its end and came to rest there"):
        Monitor(lambda state: state.t > start + 2.85,
                NavigateAction((0.0, 0.0, 0.0))).perform(robot)
    assert math.dist(robot.scene.base[:2], (0.0, 0.0)) < 1e-6


def test_a_monitor_stops_a_joint_motion_and_fallbacks_inside_it_do_not_move(robot) -> None:
    ParkArmsAction().perform(robot)
    torso = "torso_lift_joint"
    moves = []
    with pytest.raises(MonitorFired):
        Monitor(lambda state: state.joints[torso] > 0.1,
                TryInOrder([MoveTorsoAction(0.3),
                            Code(lambda ctx: moves.append(ctx.time_s) or
                                 MoveTorsoAction(0.31).perform(ctx))])).perform(robot)
    height = robot.scene.joint_positions([torso])[torso]
    assert 0.1 < height < 0.13  # braked at 1.3 cm/s soon after 0.1 m
    assert moves == []  # TryInOrder did not carry on: a fired monitor stops the step


def test_validate_always_runs_and_perform_cannot_be_overridden(robot) -> None:
    class Checked(ActionDesignator):
        def execute(self, ctx):
            return "moved"

        def validate(self, ctx, result=None):
            assert result == "moved"
            raise PlacementFailed("post-condition does not hold")

    with pytest.raises(PlacementFailed, match="post-condition"):
        Checked().perform(robot)
    assert _node(robot, "Checked")["status"] == "failed"
    with pytest.raises(TypeError, match="implements execute"):
        class Skipping(ActionDesignator):  # noqa: F841
            def perform(self, ctx):
                return None
