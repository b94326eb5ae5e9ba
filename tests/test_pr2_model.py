"""The PR2 in PyBullet and Pinocchio agree once joints are mapped by name."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from cramlite.world import World
from cramlite.world.pr2 import JointMap, pinocchio_pr2, pr2_urdf_path


def test_urdf_mesh_paths_are_resolved_to_the_installed_share_folder() -> None:
    text = pr2_urdf_path().read_text()
    assert "package://" not in text
    mesh = text.split('filename="')[1].split('"')[0]
    assert mesh.startswith("/") and mesh.endswith(".stl")
    from pathlib import Path
    assert Path(mesh).is_file()


def test_pinocchio_model_is_built_once() -> None:
    assert pinocchio_pr2() is pinocchio_pr2()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_joint_map_gives_the_same_forward_kinematics(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pr2 = pinocchio_pr2()
    with World() as world:
        robot = world.load_robot()
        joints = {}
        for name, (lo, hi) in robot.joint_limits.items():
            if hi < lo:  # continuous joint (PyBullet reports lower 0, upper -1)
                lo, hi = -np.pi, np.pi
            joints[name] = float(rng.uniform(lo, hi))
        robot.set_joint_positions(joints)
        jmap = JointMap(robot.joint_index, pr2)
        q = jmap.bullet_to_q(joints)
        back = jmap.q_to_bullet(q)
        for name, value in back.items():
            assert np.isclose(np.angle(np.exp(1j * (value - joints[name]))), 0, atol=1e-9), name
        data = pr2.model.createData()
        pin.framesForwardKinematics(pr2.model, data, q)
        for link in ["r_gripper_tool_frame", "l_gripper_tool_frame", "head_plate_frame",
                     "r_elbow_flex_link"]:
            frame = data.oMf[pr2.model.getFrameId(link)]
            pos, _ = robot.link_pose(link)
            print(link, frame.translation.round(4), np.round(pos, 4))
            assert np.allclose(frame.translation, pos, atol=1e-5)


@pytest.mark.parametrize("arm, torso", [("right", True), ("left", True), ("right", False)])
def test_link_frames_by_pinocchio_are_pybullets(arm: str, torso: bool) -> None:
    """The motion broadphase takes every link's frame from Pinocchio (the chain composed
    for all states at once): at a turned, moved base, with the other joints anywhere, they
    must be PyBullet's frames, whether the torso moves with the arm or not."""
    from cramlite.designators.context import collision_checker
    from cramlite.motion.ik import arm_joint_names
    from cramlite.world import load_setup
    from cramlite.world.bullet import p

    rng = np.random.default_rng(3)
    with World.from_setup(load_setup("v1")) as world:
        robot = world.robot
        robot.set_base_pose(0.4, -0.7, 2.2)
        robot.set_joint_positions({"l_elbow_flex_joint": -1.0, "torso_lift_joint": 0.2,
                                   "r_gripper_l_finger_joint": 0.3})
        checker = collision_checker(world)
        names = ["torso_lift_joint"] * torso + arm_joint_names(arm)
        scene = checker.scene(names, [])
        states = rng.uniform(-4.0, 4.0, size=(12, len(names)))
        if torso:
            states[:, 0] = rng.uniform(0.0, 0.3, 12)
        positions, rotations = checker.link_frames().frames(names, states, scene.query_links)
        assert positions.shape == (12, len(scene.query_links), 3)
        # (a few states are placed one by one, many all at once: both must agree)
        few = checker.link_frames().frames(names, states[:3], scene.query_links)
        assert np.allclose(few[0], positions[:3]) and np.allclose(few[1], rotations[:3])
        for s, q in enumerate(states):
            scene.set_state(q)
            bullet = p.getLinkStates(robot.body, scene.query_links,
                                     computeForwardKinematics=True,
                                     physicsClientId=world.client)
            for k, state in enumerate(bullet):
                assert np.allclose(positions[s, k], state[4], atol=1e-5)
                matrix = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
                assert np.allclose(rotations[s, k], matrix, atol=1e-5)
