"""Every action's perform() returns what it achieved (a user's plan can use it): where
the base, an item, the torso, the arms, a gripper, a drawer ended."""

from __future__ import annotations

import pytest

from cramlite import (
    CloseAction,
    MoveTorsoAction,
    NavigateAction,
    OpenAction,
    ParkArmsAction,
    SetGripperAction,
)
from cramlite.designators import simulated_robot
from cramlite.designators.motions import gripper_joints
from cramlite.world.pr2 import PARK_JOINTS
from cramlite.world.setup import load_setup


def test_actions_return_what_they_achieved() -> None:
    with simulated_robot(load_setup("c1"), backend="kinematic") as ctx:
        parked = ParkArmsAction().perform(ctx)
        assert set(parked) == {"left", "right"}
        assert parked["left"] == pytest.approx(PARK_JOINTS["left"], abs=1e-3)
        assert MoveTorsoAction(0.2).perform(ctx) == pytest.approx(0.2, abs=1e-3)
        fingers = SetGripperAction("left", "open").perform(ctx)
        assert fingers == pytest.approx(gripper_joints("left", "open"), abs=1e-3)
        where = NavigateAction((0.0, -1.5, 0.0)).perform(ctx)
        assert where == pytest.approx((0.0, -1.5, 0.0), abs=1e-3)
        drawer = ctx.scene.containers["drawer_1"]
        opened = OpenAction("drawer_1").perform(ctx)
        assert opened == pytest.approx(drawer.open_value, abs=1e-3) and opened > 0.1
        assert CloseAction("drawer_1").perform(ctx) == pytest.approx(0.0, abs=1e-3)
