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
