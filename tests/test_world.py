from __future__ import annotations

import math

import numpy as np
import pytest

from tests.conftest import skip_module_without_pybullet

skip_module_without_pybullet()

from cramlite.backends.pybullet.world import World
from cramlite.scene import PlanningScene
from cramlite.scene.transforms import yaw_quat
from cramlite.world import load_setup

SETUPS = ["v1", "v2", "v3", "v4", "v5"]


@pytest.mark.parametrize("name", SETUPS)
def test_every_item_rests_on_its_surface_after_a_second(name: str) -> None:
    setup = load_setup(name)
    scene = PlanningScene(setup)
    with World.from_setup(setup) as world:
        start = {n: np.array(o.position()) for n, o in world.objects.items()}
        world.step(1.0)
        for spec in setup.items:
            pos = np.array(world.objects[spec.name].position())
            surface = scene.surface(spec.surface)
            moved = np.linalg.norm(pos - start[spec.name])
            print(name, spec.name, pos.round(4), "moved", round(moved, 4))
            assert moved < 0.01, f"{spec.name} moved {moved:.3f} m (fell or slid)"
            assert abs(pos[2] - surface.top_z) < 0.005, f"{spec.name} not at the surface top"
            assert surface.contains_xy(pos[0], pos[1])


def test_world_loads_kitchen_robot_and_items() -> None:
    with World.from_setup(load_setup("v1")) as world:
        assert set(world.objects) == {"spoon", "breakfast-cereal", "milk", "cup", "bowl"}
        assert {"counter", "island", "fridge"} <= set(world.environment_links)
        assert world.robot is not None and len(world.robot.joint_index) > 20
        x, y, yaw = world.robot.base_pose()
        assert (x, y) == pytest.approx((-0.5, -1.8), abs=1e-6)
        assert yaw == pytest.approx(math.pi / 2, abs=1e-3)
        counter = PlanningScene(load_setup("v1")).surface("counter")
        assert counter.top_z == pytest.approx(0.85, abs=1e-3)
        assert counter.x_min == pytest.approx(1.25, abs=1e-3)


def test_two_worlds_do_not_interfere() -> None:
    setup = load_setup("v1")
    with World.from_setup(setup) as a, World.from_setup(setup) as b:
        assert a.client != b.client
        a.objects["cup"].set_pose((0.0, 0.0, 2.0), yaw_quat(0))
        a.robot.set_base_pose(1.0, 1.0, 0.0)
        a.step(0.5)
        assert b.objects["cup"].position() == pytest.approx((1.45, 0.85, 0.85), abs=2e-3)
        assert b.robot.base_pose()[:2] == pytest.approx((-0.5, -1.8))
        assert a.objects["cup"].position()[2] < 1.9  # fell under gravity in its own world
        a.close()
        assert b.objects["milk"].position() == pytest.approx((1.45, -0.15, 0.85), abs=2e-3)


def test_snapshot_restore_resets_what_a_plan_changes() -> None:
    with World.from_setup(load_setup("v2")) as world:
        snap = world.snapshot()
        world.objects["bowl"].set_pose((0.0, 0.0, 1.0))
        world.robot.set_base_pose(0.3, 0.2, 1.0)
        world.robot.set_joint_positions({"torso_lift_joint": 0.3})
        world.restore(snap)
        assert world.objects["bowl"].position() == pytest.approx(snap.objects["bowl"][0])
        assert world.robot.base_pose() == pytest.approx(snap.base)
        assert world.robot.joint_positions(["torso_lift_joint"])["torso_lift_joint"] == \
            pytest.approx(snap.joints["torso_lift_joint"])
