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


def test_oriented_boxes_are_apart_only_where_coal_finds_them_apart() -> None:
    """The broadphase's oriented test against coal's distance of the same boxes (turned at
    random, some square to each other, some alike): never "apart" where they are within
    the gap, and it finds nearly every pair that is clearly apart (it leaves out the
    edge-edge axes, so a few)."""
    from scipy.spatial.transform import Rotation

    from cramlite.scene.geometry import boxes_apart

    m = 3000
    rng = np.random.default_rng(7)
    axes_a = Rotation.random(m, random_state=1).as_matrix()
    axes_b = Rotation.random(m, random_state=2).as_matrix()
    axes_a[:300] = axes_b[:300] = np.eye(3)
    axes_b[300:600] = axes_a[300:600]
    centres_a, centres_b = rng.normal(0, 0.3, (m, 3)), rng.normal(0, 0.3, (m, 3))
    halves_a, halves_b = rng.uniform(0.01, 0.3, (m, 3)), rng.uniform(0.01, 0.3, (m, 3))
    for gap in (0.0, 0.02):
        apart = boxes_apart(axes_a, centres_a, halves_a, axes_b, centres_b, halves_b, gap)
        distances = np.empty(m)
        for i in range(m):
            result = coal.DistanceResult()
            coal.distance(coal.Box(*(2 * halves_a[i])), coal.Transform3s(axes_a[i], centres_a[i]),
                          coal.Box(*(2 * halves_b[i])), coal.Transform3s(axes_b[i], centres_b[i]),
                          coal.DistanceRequest(), result)
            distances[i] = result.min_distance
        assert not np.any(apart & (distances <= gap))
        clearly = distances > gap + 0.02
        print(gap, "apart", int(apart.sum()), "clearly apart", int(clearly.sum()))
        assert apart[clearly].mean() > 0.9


def _touch(robot, grips, arms, ignore, self_collision, p, o) -> bool:
    """The rule for a part and an obstacle, one pair at a time."""
    if o.owner in ignore and o.kind in ("kitchen", "item"):
        return False
    if o.kind in ("robot", "held") and not self_collision:
        return False
    if o.kind == "robot":
        return (robot.may_collide(p.robot_link, o.owner) if p.robot_link
                else o.owner not in grips[p.held_arm])
    if o.kind == "held":
        return p.robot_link is None or p.robot_link not in grips[arms[o.owner]]
    return True


def _meet(robot, grips, self_collision, a, b) -> bool:
    """The rule for two moving parts, one pair at a time."""
    if a.moving_joints == b.moving_joints or not self_collision:
        return False
    if a.robot_link and b.robot_link:
        return robot.may_collide(a.robot_link, b.robot_link)
    if a.robot_link is None and b.robot_link is None:
        return True
    item, link = (a, b) if a.robot_link is None else (b, a)
    return link.robot_link not in grips[item.held_arm]


def test_a_layouts_pairs_follow_the_rules_pair_by_pair() -> None:
    """The checked part-obstacle and part-part pairs of a motion's layout, worked out as
    matrices, are those the rules give one pair at a time: robot links by the SRDF and
    whether the motion moves them apart, a held item never against its own gripper,
    what the motion may touch left out, no robot pairs without self-collision."""
    from cramlite.scene.collision import HeldObject

    scene = PlanningScene(load_setup("c1"))
    collisions = SceneCollisions(scene)
    robot, grips = scene.robot, collisions.gripper_links
    cup = HeldObject("cup", "right", np.eye(4))
    queries = [(arm_joint_names("right"), [], frozenset(), True),
               (arm_joint_names("left"), [cup], frozenset({"bowl", "drawer_1"}), True),
               (["torso_lift_joint", *arm_joint_names("right")], [cup], frozenset(), True),
               (arm_joint_names("right"), [cup], frozenset({"cup"}), False)]
    for joints, held, ignore, self_collision in queries:
        layout = collisions.layout(joints, held, ignore, self_collision)
        arms = {h.name: h.arm for h in held}
        expected = [[_touch(robot, grips, arms, ignore, self_collision, p, o)
                     for o in layout.obstacles] for p in layout.parts]
        assert layout.allowed.tolist() == expected
        parts = layout.parts
        assert layout.pairs.tolist() == [[i, j] for i in range(len(parts))
                                         for j in range(i + 1, len(parts))
                                         if _meet(robot, grips, self_collision, parts[i],
                                                  parts[j])]
        assert layout.allowed.any() and (len(layout.pairs) > 0) == self_collision
