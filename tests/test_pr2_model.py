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
