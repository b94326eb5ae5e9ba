"""An item heavier than a hand of the PR2 may hold (1.8 kg) is not picked up: a red-team
setup's 50 kg box was carried one-handed on every backend, and `replay --check` passed it.
Refused before anything moves. Kinematic backend."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cramlite import simulated_robot
from cramlite.designators import AttachMotion
from cramlite.designators.failures import GraspFailed
from cramlite.world.setup import load_setup
from tests.conftest import run_cli

BOX = """<?xml version="1.0"?>
<robot name="box">
  <link name="box">
    <collision><origin xyz="0 0 0.075"/><geometry><box size="0.06 0.06 0.15"/></geometry>
    </collision>
    <inertial><origin xyz="0 0 0.075"/><mass value="{mass}"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
  </link>
</robot>
"""

SETUP = """format: 1
name: {name}
world: kitchen
robot:
  start: [-0.5, -1.8, 1.5708]
items:
  - name: box
    type: box.urdf
    pose: [1.45, 0.35, 0.85, 0.0]
    surface: counter
    category: none
    target: [-0.85, 1.3, 0.86, 0.0]
baseline_order: [box]
"""


def _setup(folder: Path, mass: float) -> Path:
    (folder / "box.urdf").write_text(BOX.format(mass=mass))
    path = folder / f"box{mass:g}.yaml"
    path.write_text(SETUP.format(name=f"box{mass:g}"))
    return path


def test_a_box_too_heavy_for_a_hand_is_not_picked_up(tmp_path: Path) -> None:
    done = run_cli("run", str(_setup(tmp_path, 50.0)), "--backend", "kinematic", "--json")
    assert done.returncode == 1, done.stderr
    result = json.loads(done.stdout)
    assert [(f["item"], f["type"], f["message"]) for f in result["failures"]] == [
        ("box", "GraspFailed", "box: 50 kg, more than a hand of the PR2 may hold (1.8 kg)")]
    # (refused before anything moved: the base stood, the box is where it was)
    assert result["base_path_m"] == 0.0
    assert result["items"]["box"]["position"] == [1.45, 0.35, 0.85]


def test_a_box_a_hand_may_hold_is_carried(tmp_path: Path) -> None:
    done = run_cli("run", str(_setup(tmp_path, 1.5)), "--backend", "kinematic", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["order"] == ["box"]


def test_attach_refuses_what_a_hand_may_not_hold(tmp_path: Path) -> None:
    with simulated_robot(load_setup(str(_setup(tmp_path, 50.0))), backend="kinematic") as ctx:
        with pytest.raises(GraspFailed, match="box: 50 kg, more than a hand"):
            AttachMotion("right", "box").perform(ctx)
        assert not ctx.scene.belief.held
