"""The planning scene's models against PyBullet's: the PR2's frames, the distances of
primitive shapes, the contacts of meshes."""

from __future__ import annotations

from pathlib import Path

import coal
import numpy as np
import pytest

from tests.conftest import skip_module_without_pybullet

skip_module_without_pybullet()

from cramlite.backends.pybullet.client import p
from cramlite.backends.pybullet.world import World
from cramlite.motion.ik import arm_joint_names
from cramlite.scene.collision import SceneCollisions
from cramlite.scene.kinematics import BatchedFrames
from cramlite.scene.models import MESH, pr2_model
from cramlite.scene.scene import PlanningScene
from cramlite.scene.transforms import planar, pose_matrix, quat_matrix
from cramlite.trace.check import _Body, penetration
from cramlite.world import load_setup
from cramlite.world.pr2 import pr2_urdf_path


def test_urdf_mesh_paths_are_resolved_to_the_installed_share_folder() -> None:
    text = pr2_urdf_path().read_text()
    assert "package://" not in text
    mesh = text.split('filename="')[1].split('"')[0]
    assert mesh.startswith("/") and mesh.endswith(".stl")
    assert Path(mesh).is_file()


def test_the_model_is_built_once_with_its_meshes_srdf_and_mimic_joints() -> None:
    robot = pr2_model()
    assert pr2_model() is robot
    assert sum(len(s) for s in robot.shapes_by_link.values()) == 32
    assert sum(s.kind == MESH for s in robot.shapes) == 31  # (the stereo camera: a box)
    assert len(robot.disabled_pairs) == 1161  # (the SRDF's 1163 entries name two pairs twice)
    links = sorted(robot.shapes_by_link)
    pairs = [(a, b) for i, a in enumerate(links) for b in links[i + 1:]
             if robot.may_collide(a, b)]
    assert len(pairs) == 239  # as pinocchio.removeCollisionPairs leaves them
    fingers = robot.with_mimics({"r_gripper_l_finger_joint": 0.3})
    assert {k for k in fingers if k.startswith("r_gripper")} == {
        "r_gripper_l_finger_joint", "r_gripper_r_finger_joint", "r_gripper_l_finger_tip_joint",
        "r_gripper_r_finger_tip_joint", "r_gripper_l_parallel_root_joint",
        "r_gripper_r_parallel_root_joint"}


def _random_joints(rng: np.random.Generator) -> dict[str, float]:
    out = {}
    for name, joint in pr2_model().joints.items():
        lo, hi = (joint.lower, joint.upper) if joint.kind != "continuous" else (-np.pi, np.pi)
        out[name] = float(rng.uniform(lo, hi))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_link_frames_agree_with_pybullet(seed: int) -> None:
    """Every link's frame from the scene's model (Pinocchio) is PyBullet's, to 1e-5 m, at a
    turned, moved base and random joints."""
    rng = np.random.default_rng(seed)
    scene = PlanningScene(load_setup("v1"))
    joints = _random_joints(rng)
    base = (0.4, -0.7, 2.2)
    with World.from_setup(scene.setup) as world:
        world.robot.set_base_pose(*base)
        world.robot.set_joint_positions({n: v for n, v in joints.items()
                                         if n in world.robot.joint_index})
        links = [n for n in world.robot.link_index if n in scene.robot.link_frames]
        mine = scene.link_matrices(links, joints, base)
        for link in links:
            pos, orn = world.robot.link_pose(link)
            assert np.allclose(mine[link][:3, 3], pos, atol=1e-5), link
            assert np.allclose(mine[link][:3, :3], quat_matrix(orn), atol=1e-5), link


@pytest.mark.parametrize("arm, torso", [("right", True), ("left", True), ("right", False)])
def test_batched_frames_are_the_models(arm: str, torso: bool) -> None:
    """A motion's frames, for many states at once (the chain composed over all of them)
    and for a few (state by state), are the model's own."""
    rng = np.random.default_rng(3)
    robot = pr2_model()
    frames = BatchedFrames(robot)
    values = _random_joints(rng)
    names = ["torso_lift_joint"] * torso + arm_joint_names(arm)
    links = [link for link in robot.shapes_by_link if set(names) & set(robot.joints_above(link))]
    states = rng.uniform(-4.0, 4.0, size=(12, len(names)))
    if torso:
        states[:, 0] = rng.uniform(0.0, 0.3, 12)
    base = planar(0.4, -0.7, 2.2)
    many = frames.frames(base, values, names, states, links)
    few = frames.frames(base, values, names, states[:3], links)
    assert np.allclose(few, many[:3])
    for s, row in enumerate(states):
        placed = robot.link_placements({**values, **dict(zip(names, row, strict=True))}, links)
        for k, link in enumerate(links):
            assert np.allclose(many[s, k], base @ placed[link], atol=1e-9)


def test_primitive_distances_agree_with_pybullet() -> None:
    """An item against the kitchen's boxes at random poses near them: the scene's
    penetration depth (coal) is PyBullet's within 1 mm."""
    setup = load_setup("v1")
    scene = PlanningScene(setup)
    collisions = SceneCollisions(scene)
    rng = np.random.default_rng(5)
    compared = 0
    with World.from_setup(setup) as world:
        kitchen = [(s, pl) for s, pl in scene.kitchen_shapes() if s.link in ("counter", "island")]
        for name in ("cup", "milk", "breakfast-cereal"):
            body = world.objects[name]
            for _ in range(40):
                shape, placement = kitchen[int(rng.integers(len(kitchen)))]
                top = placement[:3, 3] + shape.centre + [0, 0, shape.half[2]]
                position = top + rng.uniform([-0.3, -0.3, -0.06], [0.3, 0.3, 0.02])
                yaw = float(rng.uniform(-np.pi, np.pi))
                orientation = (0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2))
                body.set_pose(tuple(position), orientation)
                (item_shape, item_placement), = scene.item_shapes(
                    name, pose_matrix(position, orientation))
                mine = collisions.depth(item_shape, item_placement, shape, placement)
                index = world.environment_links[shape.link]
                points = p.getClosestPoints(body.body, world.environment, 0.0,
                                            linkIndexB=index, physicsClientId=world.client)
                theirs = max((-pt[8] for pt in points), default=0.0)
                if max(mine, theirs) > 0:
                    compared += 1
                assert mine == pytest.approx(theirs, abs=1e-3), (name, shape.link)
    assert compared > 20


def test_mesh_contacts_agree_with_pybullets_hulls_and_the_real_meshes() -> None:
    """Robot links near the kitchen at random configurations: every contact the scene
    reports deeper than 1 cm is one in PyBullet's convex hulls too, and every hull contact
    deeper than 1 cm that the real meshes confirm (the trace check's volumetric test) is
    reported by the scene."""
    setup = load_setup("v1")
    scene = PlanningScene(setup)
    collisions = SceneCollisions(scene)
    rng = np.random.default_rng(11)
    checker_bodies = {}
    seen = {"scene": 0, "hulls": 0}
    with World.from_setup(setup) as world:
        kitchen = {s.link: (s, pl) for s, pl in scene.kitchen_shapes()}
        for _ in range(150):
            joints = _random_joints(rng)
            base = (float(rng.uniform(0.75, 0.95)), float(rng.uniform(-0.6, 0.8)),
                    float(rng.uniform(-0.4, 0.4)))
            world.robot.set_base_pose(*base)
            world.robot.set_joint_positions({n: v for n, v in joints.items()
                                             if n in world.robot.joint_index})
            frames = scene.link_matrices(list(scene.robot.shapes_by_link), joints, base)
            for link in ("counter", "counter_body"):
                shape, placement = kitchen[link]
                index = world.environment_links[link]
                for robot_link, shapes in scene.robot.shapes_by_link.items():
                    robot_shape = shapes[0]
                    placed = frames[robot_link] @ robot_shape.in_link
                    mine = collisions.depth(robot_shape, placed, shape, placement)
                    points = p.getClosestPoints(
                        world.robot.body, world.environment, 0.0,
                        linkIndexA=world.robot.link_index[robot_link], linkIndexB=index,
                        physicsClientId=world.client)
                    hull = max((-pt[8] for pt in points), default=0.0)
                    if mine > 0.01:
                        seen["scene"] += 1
                        assert hull > 0, (robot_link, link, mine)
                    if hull > 0.01:
                        key = id(robot_shape)
                        body = checker_bodies.setdefault(key, _Body(robot_link, "robot",
                                                                    robot_link, robot_shape))
                        other = checker_bodies.setdefault(id(shape), _Body(link, "kitchen",
                                                                           link, shape))
                        real = penetration(body, placed, other, placement,
                                           np.full(3, -50.0), np.full(3, 50.0), 0.0)
                        if real > 0.01:
                            seen["hulls"] += 1
                            assert mine > 0.005, (robot_link, link, hull, real, mine)
    print(seen)
    assert seen["scene"] > 10 and seen["hulls"] > 10


def test_coal_sees_no_mesh_inside_a_mesh_and_the_scene_does() -> None:
    """coal's test sees surfaces that cross: a fingertip wholly inside the other arm's
    shoulder housing crosses none. The scene's check sees it (and the trace check)."""
    robot = pr2_model()
    scene = PlanningScene(load_setup("v1"))
    collisions = SceneCollisions(scene)
    shoulder = robot.shapes_by_link["r_shoulder_pan_link"][0]
    tip = robot.shapes_by_link["l_gripper_l_finger_tip_link"][0]
    inside = np.eye(4)
    inside[:3, 3] = [-0.03, 0.0, -0.02]  # 9 cm deep in the housing (where the fingertip's
    # frame is: the tip itself reaches at most 6 cm from it)
    result = coal.CollisionResult()
    coal.collide(shoulder.geometry, coal.Transform3s(), tip.geometry,
                 coal.Transform3s(inside[:3, :3], inside[:3, 3]), coal.CollisionRequest(),
                 result)
    assert not result.isCollision()  # (what the scene must not rely on)
    assert collisions.enclosed(shoulder, np.eye(4), tip, inside)
    assert collisions.depth(shoulder, np.eye(4), tip, inside) > 0.05
    real = penetration(_Body("s", "robot", "s", shoulder), np.eye(4),
                       _Body("t", "robot", "t", tip), inside, np.full(3, -1.0), np.full(3, 1.0),
                       0.01)
    assert real > 0.05
    away = np.eye(4)
    away[:3, 3] = shoulder.centre + [0.6, 0.0, 0.0]
    assert not collisions.enclosed(shoulder, np.eye(4), tip, away)
