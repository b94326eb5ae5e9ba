"""The actions users asked for beyond fetch and place: LookAtAction points the head (a
checked, timed motion, traced), SetGripperAction opens and closes an empty gripper, and
PickAndPlaceAction picks up and puts down from where the robot stands."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from cramlite.designators import (
    GraspFailed,
    LookAtAction,
    MotionPlanningFailed,
    MoveTorsoAction,
    NavigateAction,
    ParkArmsAction,
    PickAndPlaceAction,
    SetGripperAction,
    simulated_robot,
)
from cramlite.designators.head import PAN, TILT, gaze_error_deg
from cramlite.designators.motions import gripper_joints
from cramlite.world.setup import load_setup


def test_look_at_points_the_head_at_an_item_and_a_point_and_refuses_its_chin(
        tmp_path: Path) -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        ctx.open_trace(tmp_path / "look.jsonl", "v1", "look", "none", 0, "kinematic")
        ParkArmsAction().perform(ctx)
        before = ctx.time_s
        point = LookAtAction("cup").perform(ctx)
        head = ctx.modules.joint_positions([PAN, TILT])
        assert gaze_error_deg(ctx, point) < 0.1 and head[PAN] < -0.3  # (the cup: right)
        assert ctx.time_s > before  # (a timed motion, not a jump)
        LookAtAction((-0.85, 1.75, 0.9)).perform(ctx)
        assert ctx.modules.joint_positions([PAN])[PAN] > 0
        with pytest.raises(MotionPlanningFailed, match="head_tilt_joint"):
            LookAtAction((-0.5, -1.6, 0.0)).perform(ctx)  # straight down: below its chin
        ctx.trace.close()
    lines = [json.loads(x) for x in (tmp_path / "look.jsonl").read_text().splitlines()]
    joints = lines[0]["joints"]
    pans = {round(s["q"][joints.index(PAN)], 3) for s in lines[1:]}
    assert len(pans) > 10  # the head turned through many traced states


def test_set_gripper_opens_and_closes_an_empty_gripper_and_refuses_a_full_one() -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic", seed=3) as ctx:
        SetGripperAction("left", "open").perform(ctx)
        wanted = gripper_joints("left", "open")
        now = ctx.modules.joint_positions(list(wanted))
        assert all(abs(now[n] - v) < 1e-6 for n, v in wanted.items())
        SetGripperAction("left", "close").perform(ctx)
        closed = gripper_joints("left", "close")
        now = ctx.modules.joint_positions(list(closed))
        assert all(abs(now[n] - v) < 1e-6 for n, v in closed.items())
        ParkArmsAction().perform(ctx)
        NavigateAction((0.85, 0.35 + 0.188, 0.0)).perform(ctx)  # in front of the spoon
        where = PickAndPlaceAction("spoon", (1.45, 0.2, 0.85), arms=["right"]).perform(ctx)
        assert where == pytest.approx((1.45, 0.2, 0.85), abs=0.01)
        assert not ctx.holding and ctx.base_path_m > 2.0
        from cramlite.designators import PickUpAction

        PickUpAction("spoon", arms=["right"]).perform(ctx)
        with pytest.raises(GraspFailed, match="holds spoon"):
            SetGripperAction("right", "open").perform(ctx)


def test_detect_does_not_see_the_cup_behind_the_cupboard_door_and_sees_it_open() -> None:
    from cramlite.designators import DetectAction, MoveTorsoAction, ObjectNotFound

    with simulated_robot(load_setup("c1"), backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(0.25).perform(ctx)
        ctx.modules.state.belief.base = (0.5, 1.75, 0.0)  # (put before the cupboard)
        ctx.observe()
        LookAtAction("cup").perform(ctx)
        assert "cup" not in DetectAction().perform(ctx)  # the closed door hides it
        with pytest.raises(ObjectNotFound, match="cup"):
            DetectAction("cup").perform(ctx)
        ctx.modules.state.belief.world_joints["cupboard_door_joint"] = 2.3  # swung open
        ctx.observe()
        seen = DetectAction("cup").perform(ctx)
        assert seen["cup"] == ctx.scene.object_pose("cup")
        noisy = [DetectAction(noise_m=0.01, seed=5).perform(ctx)["cup"][0] for _ in range(2)]
        assert noisy[0] == noisy[1] != seen["cup"][0]  # (seeded: the same noise again)
        LookAtAction((-0.85, 1.2, 0.9)).perform(ctx)  # the island, behind the robot's left
        assert "cup" not in DetectAction().perform(ctx)  # (out of view)


def test_look_at_turns_the_head_the_short_way_across_its_back() -> None:
    """Looking behind on one side and then on the other: the pan's correction passes
    pi, and the equivalent angle within the joint's limits is taken (not a refusal)."""
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        x, y, yaw = ctx.modules.state.belief.base
        behind = [(x + 1.5 * math.cos(yaw + a), y + 1.5 * math.sin(yaw + a), 1.2)
                  for a in (math.radians(165), math.radians(-165))]
        LookAtAction(behind[0]).perform(ctx)
        assert ctx.modules.joint_positions([PAN])[PAN] > 2.5
        point = LookAtAction(behind[1]).perform(ctx)
        assert ctx.modules.joint_positions([PAN])[PAN] < -2.5
        assert gaze_error_deg(ctx, point) < 0.1
        # from there, a point close by on the left (a turn of nearly 2 rad with the
        # camera off the pan axis) is met to within a hundredth of a degree
        MoveTorsoAction(0.25).perform(ctx)
        near = (x + 0.4 * math.cos(yaw + math.pi / 2), y + 0.4 * math.sin(yaw + math.pi / 2),
                0.7)
        assert gaze_error_deg(ctx, LookAtAction(near).perform(ctx)) < 0.01


def test_a_place_with_nothing_under_it_is_refused_before_anything_moves() -> None:
    from cramlite.designators import PlacementFailed, TransportAction

    with simulated_robot(load_setup("v1"), backend="kinematic") as robot:
        for target in ((-0.9, 1.3, 1.3), (-0.9, 1.3, 0.6), (5.0, 5.0, 0.86)):  # air, in, off
            with pytest.raises(PlacementFailed, match="rests on nothing"):
                TransportAction("cup", target=target).perform(robot)
        assert robot.time_s == 0.0 and not robot.holding  # (refused before any motion)


def test_a_container_opened_for_an_item_not_taken_out_is_closed_again() -> None:
    from cramlite.designators import ObjectUnreachable, TransportAction

    with simulated_robot(load_setup("c1"), backend="kinematic") as robot:
        fridge = robot.scene.surface("fridge")  # (a surface no hand puts the spoon on)
        top = ((fridge.x_min + fridge.x_max) / 2, (fridge.y_min + fridge.y_max) / 2,
               fridge.top_z)
        with pytest.raises(ObjectUnreachable):
            TransportAction("spoon", target=top).perform(robot)  # (it is in drawer_1)
        names = [node["name"] for node in robot.tasks.as_list()[0]["children"]]
        assert "OpenAction" in names and "CloseAction" in names, names
        assert robot.opened == [] and robot.scene.world_joint_positions()["drawer_1_joint"] == 0
