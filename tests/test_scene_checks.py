"""The planning scene's checks at their edges: a link may press TOLERANCE_M into an item
(contact is not collision), never deeper; an item wholly inside a link (no surfaces
cross, so coal sees nothing) is a collision. With the robot's real meshes."""

from __future__ import annotations

import coal
import numpy as np
import pytest

from cramlite.motion.ik import arm_joint_names
from cramlite.scene.collision import TOLERANCE_M, SceneCollisions
from cramlite.scene.scene import PlanningScene
from cramlite.world.setup import load_setup


def _gripper_lowest_point(scene: PlanningScene) -> np.ndarray:
    """The lowest point of the right gripper's meshes (the arm stretched forward)."""
    links = [name for name in scene.robot.shapes_by_link if name.startswith("r_gripper")]
    frames = scene.link_matrices(links)
    points = np.vstack([shape.vertices @ placed[:3, :3].T + placed[:3, 3]
                        for link in links for shape in scene.robot.shapes_by_link[link]
                        if shape.vertices is not None
                        for placed in [frames[link] @ shape.in_link]])
    return points[np.argmin(points[:, 2])]


@pytest.mark.parametrize(("depth_mm", "free"), [(0.0, True), (TOLERANCE_M * 1e3 - 1.5, True),
                                                (TOLERANCE_M * 1e3 + 1.5, False), (30.0, False)])
def test_the_gripper_may_press_the_tolerance_into_a_box_and_no_deeper(depth_mm: float,
                                                                      free: bool) -> None:
    scene = PlanningScene(load_setup("v1"))
    lowest = _gripper_lowest_point(scene)
    height = 2 * scene.items["milk"].model.shapes[0].half[2]
    # the milk box's top face depth_mm above the gripper's lowest point, under it
    top = lowest[2] + depth_mm / 1e3
    scene.belief.poses["milk"] = ((float(lowest[0]), float(lowest[1]), float(top - height)),
                                  (0.0, 0.0, 0.0, 1.0))
    check = SceneCollisions(scene).check(arm_joint_names("right"))
    assert check.is_free(check.current()) is free
    # the same through a motion's check of several states
    assert check.states_free(np.repeat(check.current()[None], 3, axis=0)) is free


def test_an_item_wholly_inside_a_moving_link_is_a_collision() -> None:
    scene = PlanningScene(load_setup("v1"))
    torso = scene.robot.shapes_by_link["torso_lift_link"][0]
    placed = scene.link_matrices(["torso_lift_link"])["torso_lift_link"] @ torso.in_link
    centre = placed[:3, :3] @ torso.centre + placed[:3, 3]
    cup = scene.items["cup"].model.shapes[0]
    bottom = centre - cup.in_link[:3, 3]  # (an item's frame is its bottom face's centre)
    scene.belief.poses["cup"] = (tuple(float(v) for v in bottom), (0.0, 0.0, 0.0, 1.0))
    cup_placed = scene.item_matrix("cup") @ cup.in_link
    crossing = coal.CollisionResult()
    coal.collide(torso.geometry, coal.Transform3s(placed[:3, :3], placed[:3, 3]), cup.geometry,
                 coal.Transform3s(cup_placed[:3, :3], cup_placed[:3, 3]),
                 coal.CollisionRequest(), crossing)
    assert not crossing.isCollision()  # no surfaces cross: wholly inside
    check = SceneCollisions(scene).check(["torso_lift_joint"])
    assert not check.is_free(check.current())
    assert not check.states_free(np.repeat(check.current()[None], 2, axis=0))
    scene.belief.poses["cup"] = ((bottom[0] + 1.0, bottom[1], bottom[2]), (0, 0, 0, 1.0))
    assert SceneCollisions(scene).check(["torso_lift_joint"]).is_free(check.current())


def test_a_thin_wall_through_a_link_is_a_collision() -> None:
    """The bowl's 6 mm walls are thinner than twice the tolerance: no point of the arm's
    mesh can be deeper than 3 mm in one, yet a wall may cut right through the arm (an
    audit of c3 found the upper arm 1.8 cm around a wall)."""
    scene = PlanningScene(load_setup("v1"))
    link = "r_forearm_link"
    forearm = scene.robot.shapes_by_link[link][0]
    placed = scene.link_matrices([link])[link] @ forearm.in_link
    centre = placed[:3, :3] @ forearm.centre + placed[:3, 3]
    bowl = scene.items["bowl"].model
    wall = max(bowl.shapes, key=lambda s: s.in_link[0, 3])  # the wall at +x
    assert min(wall.half) < TOLERANCE_M  # (thin)
    # the wall's middle at the forearm's top surface: half of it inside, half out
    top = max(v @ placed[:3, :3].T[:, 2] + placed[2, 3] for v in forearm.vertices)
    bottom = np.array([centre[0], centre[1], top]) - wall.in_link[:3, 3]
    scene.belief.poses["bowl"] = (tuple(float(v) for v in bottom), (0.0, 0.0, 0.0, 1.0))
    check = SceneCollisions(scene).check(arm_joint_names("right"))
    assert not check.is_free(check.current())
    assert not check.states_free(np.repeat(check.current()[None], 2, axis=0))
    # and the message says how deep: the wall's points inside the forearm
    contact = max((c for c in check.contacts() if c.what == "r_forearm_link"),
                  key=lambda c: c.depth_m)
    assert contact.depth_m > 0.01, contact.describe()
    scene.belief.poses["bowl"] = ((bottom[0], bottom[1], bottom[2] + 1.0), (0, 0, 0, 1.0))
    assert SceneCollisions(scene).check(arm_joint_names("right")).is_free(check.current())
