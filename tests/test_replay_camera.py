"""Replays a person can follow (#27): captions say what the robot does and what it
carries, and the camera can follow the robot or look straight down."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cramlite.render.camera import replay_view
from cramlite.trace.replay import doing
from tests.conftest import run_cli


@pytest.mark.parametrize("state, words", [
    ({"action": {"name": "ParkArmsAction", "object": "bowl"}, "held": {"bowl": "right"}},
     "carrying bowl (right hand): parking the arms"),
    ({"action": {"name": "PlaceAction", "object": "bowl"}, "held": {"bowl": "right"}},
     "carrying bowl (right hand): putting down bowl"),
    ({"action": {"name": "OpenAction", "object": "drawer_1"}, "held": {}}, "opening drawer_1"),
    ({"action": {"name": "NavigateAction", "object": None}, "held": {"cup": "left"}},
     "carrying cup (left hand): driving"),
    ({"action": None, "held": {}}, ""),
])
def test_captions_name_what_the_robot_does_and_carries(state, words: str) -> None:
    assert doing(state) == words


def test_the_follow_camera_looks_where_the_robot_faces() -> None:
    view = replay_view("follow", (1.0, 2.0, math.pi / 2))
    assert view["target"][:2] == pytest.approx((1.0, 2.6))  # (0.6 m ahead of it)
    assert view["yaw_deg"] == pytest.approx(0.0)  # (behind it: looking along +y)
    assert replay_view("top", (1.0, 2.0, 0.0))["pitch_deg"] < -85
    with pytest.raises(ValueError, match="expected one of fixed, top, follow"):
        replay_view("sideways", (0, 0, 0))


def test_replay_draws_each_camera_and_refuses_an_unknown_one(tmp_path: Path) -> None:
    from PIL import Image

    trace = tmp_path / "v1.jsonl"
    assert run_cli("run", "v1", "--backend", "kinematic", "--trace", str(trace)).returncode == 0
    frames = {}
    for mode in ("fixed", "top", "follow"):
        out = tmp_path / f"{mode}.gif"
        result = run_cli("replay", str(trace), "--out", str(out), "--camera", mode,
                         "--speed", "40", "--fps", "1", "--backend", "kinematic")
        assert result.returncode == 0, result.stderr
        with Image.open(out) as gif:
            gif.seek(gif.n_frames // 2)
            frames[mode] = np.asarray(gif.convert("RGB"), dtype=float)
    assert np.abs(frames["fixed"] - frames["top"]).mean() > 5
    assert np.abs(frames["fixed"] - frames["follow"]).mean() > 5
    bad = run_cli("replay", str(trace), "--out", str(tmp_path / "x.gif"), "--camera", "side")
    assert bad.returncode == 2 and "invalid choice: 'side'" in bad.stderr
