"""What a plan asks of a designator that no robot could do, or that is no argument at all,
is refused before anything moves: a joint beyond its URDF limit, a joint the robot does not
have, a value that is no number (a red-team pass of plans written from the docs found the
torso driven to 0.5 m of its 0.31 m, and raw KeyErrors). Kinematic backend."""

from __future__ import annotations

import math

import pytest

from cramlite.designators import (
    MotionPlanningFailed,
    MoveArmJointsMotion,
    MoveTorsoAction,
    MoveTorsoMotion,
    simulated_robot,
)
from cramlite.world.setup import load_setup


@pytest.mark.parametrize(("designator", "expected"), [
    (MoveTorsoAction(0.5), "torso_lift_joint to 0.5 m is beyond its limits [0, 0.31] m"),
    (MoveTorsoAction(-0.1), "torso_lift_joint to -0.1 m is beyond its limits"),
    (MoveTorsoMotion(0.6), "torso_lift_joint to 0.6 m is beyond its limits"),
    (MoveArmJointsMotion({"l_elbow_flex_joint": 1.0}),
     "l_elbow_flex_joint to 1 rad is beyond its limits [-2.3213, 0] rad"),
])
def test_a_joint_goal_beyond_its_limit_is_refused_and_nothing_moves(designator,
                                                                    expected) -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        before = ctx.modules.joint_positions(None)
        with pytest.raises(MotionPlanningFailed, match=expected.replace("[", r"\[")):
            designator.perform(ctx)
        assert ctx.modules.joint_positions(None) == before
        assert ctx.time_s == 0.0


@pytest.mark.parametrize(("joints", "expected"), [
    ({"l_knee_joint": 1.0}, "no joint 'l_knee_joint' on the robot"),
    ({"l_elbow_flex_joint": math.nan}, "l_elbow_flex_joint: expected a finite number"),
    ({"torso_lift_joint": "high"}, "torso_lift_joint: expected a finite number, got 'high'"),
])
def test_a_joint_goal_that_is_no_argument_is_a_clear_value_error(joints, expected) -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx, \
            pytest.raises(ValueError, match=expected):
        MoveArmJointsMotion(joints).perform(ctx)


def test_a_continuous_joint_takes_any_angle() -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        MoveArmJointsMotion({"r_forearm_roll_joint": 4.0}).perform(ctx)
        value = ctx.modules.joint_positions(["r_forearm_roll_joint"])["r_forearm_roll_joint"]
        assert math.isclose(math.remainder(value - 4.0, 2 * math.pi), 0.0, abs_tol=1e-6)


def test_a_move_motion_through_the_counter_is_refused_and_nothing_moves() -> None:
    from cramlite.designators import MoveMotion, NavigationFailed

    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        start = tuple(ctx.scene.base)
        with pytest.raises(NavigationFailed, match=r"not free: the base would not fit at \("):
            MoveMotion([(2.0, 0.0, 0.0)]).perform(ctx)
        assert tuple(ctx.scene.base) == start and ctx.time_s == 0.0
        with pytest.raises(ValueError,
                           match=r"waypoint 0 \(x, y, yaw\): expected 3 finite numbers"):
            MoveMotion([(math.nan, 0.0, 0.0)]).perform(ctx)


def test_a_move_motion_starts_where_the_base_stands(tmp_path) -> None:
    """Its first waypoint elsewhere: the base drives there first (it jumped there)."""
    from cramlite.designators import MoveMotion
    from cramlite.trace import read_trace

    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        ctx.open_trace(tmp_path / "move.jsonl", "v1", "test", "none", 0, "kinematic")
        MoveMotion([(-0.5, -1.0, math.pi / 2), (-0.5, -0.8, math.pi / 2)]).perform(ctx)
        assert math.dist(ctx.scene.base[:2], (-0.5, -0.8)) < 1e-6
    states = read_trace(tmp_path / "move.jsonl").states
    steps = [math.dist(a["base"][:2], b["base"][:2])
             for a, b in zip(states, states[1:], strict=False)]
    assert len(steps) > 5 and max(steps) < 0.1, max(steps)


def test_a_gripper_holds_only_what_is_between_its_fingers_and_opens_only_to_let_go(
        tmp_path) -> None:
    """AttachMotion of a cup 3 m away carried it along; MoveGripperMotion opened a full
    hand in the air; DetachMotion left the hand (and the trace) still holding."""
    from cramlite.designators import (
        AttachMotion,
        DetachMotion,
        FetchAction,
        GraspFailed,
        MoveGripperMotion,
        ParkArmsAction,
    )
    from cramlite.trace import read_trace
    from cramlite.trace.physics import physics_findings

    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        ctx.open_trace(tmp_path / "hand.jsonl", "v1", "test", "none", 0, "kinematic")
        ParkArmsAction().perform(ctx)
        with pytest.raises(GraspFailed, match=r"cup: 3\.\d\d m from the left gripper's"):
            AttachMotion("left", "cup").perform(ctx)
        assert ctx.scene.belief.held == {}
        MoveTorsoAction(0.25).perform(ctx)
        arm = FetchAction("cup", target=(-1.0, 1.1, 0.86)).perform(ctx).arm
        with pytest.raises(GraspFailed, match="would drop it in the air"):
            MoveGripperMotion(arm, "open").perform(ctx)
        with pytest.raises(GraspFailed, match="already in the"):
            AttachMotion("right" if arm == "left" else "left", "cup").perform(ctx)
        other = "right" if arm == "left" else "left"
        with pytest.raises(GraspFailed, match=f"not in the {other} hand \\(in the {arm} hand"):
            DetachMotion(other, "cup").perform(ctx)
        DetachMotion(arm, "cup").perform(ctx)  # (in the air: the trace check says so)
        assert ctx.holding == {} and ctx.scene.belief.held == {}
        ctx.record_state()
    kinds = {f.kind for f in physics_findings(read_trace(tmp_path / "hand.jsonl"))}
    assert "support" in kinds


@pytest.mark.parametrize(("make", "expected"), [
    (lambda d: d.ParkArmsAction("middle"), "arm must be 'left', 'right' or 'both'"),
    (lambda d: d.NavigateAction((math.nan, 0.0, 0.0)), "expected 3 finite numbers"),
    (lambda d: d.NavigateAction((math.inf, 0.0, 0.0)), "expected 3 finite numbers"),
    (lambda d: d.NavigateAction([0.0, 0.0]), r"target \(x, y, yaw\): expected 3 finite"),
    (lambda d: d.LookAtAction((1.0, 2.0)), "LookAtAction: target: expected 3"),
    (lambda d: d.Repeat(d.ParkArmsAction(), -1), "times must be a whole number >= 0"),
    (lambda d: d.Retry(d.ParkArmsAction(), 0), "attempts must be a whole number >= 1"),
])
def test_a_designator_written_with_no_usable_argument_is_refused_where_it_is_written(
        make, expected) -> None:
    """(They escaped as KeyError, ValueError from a float conversion deep in the base
    checker, OverflowError or IndexError when performed.)"""
    import cramlite.designators as d

    with pytest.raises(ValueError, match=expected):
        make(d)


def test_looking_at_an_object_that_is_not_there_is_object_not_found() -> None:
    from cramlite.designators import LookAtAction, ObjectNotFound

    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx, \
            pytest.raises(ObjectNotFound, match="teapot: no such object; expected one of"):
        LookAtAction("teapot").perform(ctx)


def test_failures_say_what_is_in_the_way() -> None:
    """A goal inside the counter and a pick out of a closed drawer said only "no path" and
    "no arm and grasp reaches it"."""
    from cramlite.designators import (
        NavigateAction,
        NavigationFailed,
        ObjectUnreachable,
        ParkArmsAction,
        PickUpAction,
    )

    with simulated_robot(load_setup("c1"), backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        with pytest.raises(NavigationFailed, match=r"\(2.00, 0.00, 0 deg\): the base does "
                                                   "not fit there"):
            NavigateAction((2.0, 0.0, 0.0)).perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        NavigateAction((0.75, -0.7, 0.0)).perform(ctx)
        with pytest.raises(ObjectUnreachable, match="drawer_1, which holds it, is closed: "
                                                    r"OpenAction\('drawer_1'\) first"):
            PickUpAction("spoon").perform(ctx)


@pytest.mark.parametrize(("field", "value"), [("turn_accel_rad_s2", math.nan),
                                              ("drive_accel_m_s2", 0.0),
                                              ("drive_speed_m_s", -1.0),
                                              ("max_candidates", 0)])
def test_execution_options_that_no_motion_could_follow_are_refused(field, value) -> None:
    """(A NaN acceleration left braking no profile to fit, and it said the motion was
    near its end.)"""
    from cramlite.designators import ExecutionOptions

    with pytest.raises(ValueError, match=f"ExecutionOptions.{field}: expected"):
        ExecutionOptions(**{field: value})
