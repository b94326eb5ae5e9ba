"""The MuJoCo backend: the world it loads has the planning scene's kinematics, a released
item settles under MuJoCo's physics, a drawer carries what is inside it, pictures and GIFs
render offscreen, and a missing OpenGL is one line. (The agreement of whole trials with the
pybullet backend is in test_backends.py.)"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT, run_cli

pytestmark = pytest.mark.skipif(importlib.util.find_spec("mujoco") is None,
                                reason="mujoco is not installed (pip install 'cramlite[mujoco]')")


@pytest.fixture(scope="module")
def c1_world():
    from cramlite.backends.mujoco.world import MujocoWorld
    from cramlite.world.setup import load_setup

    with MujocoWorld(load_setup("c1")) as world:
        yield world


def test_every_joint_and_link_of_the_scene_is_in_mujoco_with_the_same_kinematics(
        c1_world) -> None:
    from cramlite.scene.scene import PlanningScene

    world = c1_world
    start = world.snapshot()
    scene = PlanningScene(world.setup)
    assert set(scene.robot.joints) <= set(world.robot_qpos)
    assert set(scene.kitchen.joints) == set(world.world_qpos)
    rng = np.random.default_rng(3)
    for _ in range(3):
        joints = {n: float(rng.uniform(*world.robot_limits[n])) for n in scene.robot.joints}
        joints = scene.robot.with_mimics(joints)  # (MuJoCo's equalities are not solved here)
        base = (float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)),
                float(rng.uniform(-math.pi, math.pi)))
        drawers = {n: 0.5 * c.open_value for n, c in
                   ((c.joint, c) for c in world.containers.values())}
        world.set_base_pose(*base)
        world.set_joint_positions(joints)
        for name, value in drawers.items():
            world.data.qpos[world.world_qpos[name]] = value
        world.forward()
        robot = scene.link_matrices(list(scene.robot.link_frames), joints, base)
        for link, frame in robot.items():
            position, _ = world.link_pose(link)
            assert np.allclose(position, frame[:3, 3], atol=1e-5), link
        assert "r_gripper_tool_frame" in robot and "l_gripper_tool_frame" in robot
        kitchen = scene.kitchen_frames(drawers)
        for link, frame in kitchen.items():
            assert np.allclose(world.link_matrix(link), frame, atol=1e-5), link
    world.restore(start)


def test_a_released_item_falls_and_settles_at_rest_on_its_surface() -> None:
    from cramlite.backends.mujoco import MujocoBackend
    from cramlite.scene.transforms import tilt_deg
    from cramlite.world.setup import load_setup

    setup = load_setup("v1")
    with MujocoBackend(setup) as backend:
        x, y, z = setup.item("cup").pose.xyz
        tilted = (math.sin(math.radians(4) / 2), 0.0, 0.0, math.cos(math.radians(4) / 2))
        backend.world.set_object_pose("cup", (x, y, z + 0.05), tilted)  # 5 cm up, tilted
        backend.modules.settle(2.0, ["cup"])
        (sx, sy, sz), orientation = backend.modules.object_pose("cup")
        assert abs(sz - z) < 0.001 and math.dist((sx, sy), (x, y)) < 0.01
        assert tilt_deg(orientation) < 0.5
        assert max(backend.world.object_speed("cup")) < 0.05
        # (it fell: physics ran, not a reset)
        assert backend.modules.simulator_report()["physics_steps"] > 50
        backend.reset()
        assert backend.modules.object_pose("cup")[0] == pytest.approx((x, y, z), abs=1e-9)


def test_an_opened_drawer_carries_what_is_inside_it(c1_world) -> None:
    from cramlite.backends.mujoco.modules import MujocoModules
    from cramlite.motion.trajectory import JointTrajectory

    world = c1_world
    start = world.snapshot()
    drawer = next(c for c in world.containers.values() if world.items_inside(c))
    (inside,) = world.items_inside(drawer)[:1]
    before = np.array(world.object_pose(inside)[0])
    modules = MujocoModules(world)
    values = np.linspace(0.0, drawer.open_value, 5)
    trajectory = JointTrajectory(names=(), positions=np.zeros((5, 0)),
                                 times=np.linspace(0, 1, 5), world={drawer.joint: values})
    seen = []
    modules.execute_joint_trajectory(trajectory, on_state=lambda i: seen.append(
        world.object_pose(inside)[0]))
    moved = np.array(world.object_pose(inside)[0]) - before
    assert np.linalg.norm(moved) == pytest.approx(abs(drawer.open_value), abs=1e-6)
    assert world.world_joint_positions()[drawer.joint] == pytest.approx(drawer.open_value)
    assert len({tuple(np.round(p, 6)) for p in seen}) == 5  # along the way, not at the end
    world.restore(start)


def test_show_and_a_replayed_gif_render_with_mujoco(tmp_path: Path) -> None:
    from PIL import Image

    png = tmp_path / "v1.png"
    shown = run_cli("show", "v1", "--backend", "mujoco", "--out", str(png), "--width", "320",
                    "--height", "240")
    assert shown.returncode == 0, shown.stderr
    assert "mujoco" in shown.stdout
    with Image.open(png) as image:
        pixels = np.asarray(image.convert("RGB"))
    assert pixels.shape == (240, 320, 3) and pixels.std() > 20  # (a scene, not a blank)
    # a trial on mujoco, its trace (`replay --check` of one: tests/test_other_pythons.py) and
    # a GIF of a short trace drawn by MuJoCo, one frame per tenth of a second
    from tests.test_trace import write

    ran = run_cli("run", "v2", "--backend", "mujoco", "--json")
    assert ran.returncode == 0, ran.stderr
    assert json.loads(ran.stdout)["backend"] == "mujoco"
    states = [(0.25 * i, [-0.5, -1.8 + 0.1 * i, math.pi / 2]) for i in range(7)]  # 1.5 s
    trace = write(tmp_path / "short.jsonl", states)
    gif = tmp_path / "short.gif"
    done = run_cli("replay", str(trace), "--backend", "mujoco", "--out", str(gif),
                   "--width", "160", "--height", "120")
    assert done.returncode == 0, done.stderr
    assert "drawn as the mujoco backend draws" in done.stdout
    with Image.open(gif) as frames:
        assert frames.n_frames == 16
        frames.seek(0)
        first = frames.convert("RGB").tobytes()
        frames.seek(15)
        assert frames.convert("RGB").tobytes() != first  # the robot drove


def test_no_opengl_is_one_line_naming_what_to_install(tmp_path: Path) -> None:
    env = {**os.environ, "MUJOCO_GL": "disable"}
    done = subprocess.run([sys.executable, "-m", "cramlite", "show", "v1", "--backend",
                           "mujoco", "--out", str(tmp_path / "x.png")], capture_output=True,
                          text=True, cwd=ROOT, env=env, timeout=300)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "EGL" in done.stderr and "cramlite[mujoco]" in done.stderr
    ran = subprocess.run([sys.executable, "-m", "cramlite", "run", "v1", "--backend", "mujoco"],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert ran.returncode == 0 and "on mujoco: success" in ran.stdout, ran.stderr  # (no GL)
    env["MUJOCO_GL"] = "nonsense"  # (MuJoCo's import fails with it: imported without GL)
    bad = subprocess.run([sys.executable, "-m", "cramlite", "run", "v1", "--backend", "mujoco"],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert bad.returncode == 0 and "on mujoco: success" in bad.stdout, bad.stderr
    drawn = subprocess.run([sys.executable, "-m", "cramlite", "show", "v1", "--backend",
                            "mujoco", "--out", str(tmp_path / "y.png")], capture_output=True,
                           text=True, cwd=ROOT, env=env, timeout=300)
    assert drawn.returncode == 2 and drawn.stderr.count("\n") == 1, drawn.stderr
    assert "MUJOCO_GL=nonsense" in drawn.stderr and "invalid value" in drawn.stderr
