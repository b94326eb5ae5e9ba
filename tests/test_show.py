from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.conftest import run_cli


def test_show_v1_writes_an_image_with_kitchen_robot_and_items(tmp_path: Path) -> None:
    out = tmp_path / "v1.png"
    result = run_cli("show", "v1", "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    image = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert image.shape == (768, 1024, 3)

    def pixels_near(rgb: tuple[int, int, int], tol: int = 40) -> int:
        return int((np.abs(image - np.array(rgb)).max(axis=2) < tol).sum())

    # cereal box (yellow), bowl (red), cup (blue), counter (brown), robot (black arms)
    counts = {name: pixels_near(rgb) for name, rgb in {
        "cereal": (230, 178, 38), "bowl": (216, 76, 64), "cup": (51, 115, 204),
        "counter": (140, 107, 76), "robot": (10, 10, 10)}.items()}
    print(counts)
    for name, count in counts.items():
        assert count > 50, f"{name} not visible ({count} px)"


@pytest.mark.parametrize(("args", "fragment"), [
    (["--width", "0"], "--width: expected a whole number of pixels in [1, 4096], got '0'"),
    (["--width", "-5"], "--width: expected a whole number of pixels in [1, 4096], got '-5'"),
    (["--height", "100000"], "--height: expected a whole number of pixels in [1, 4096]"),
    (["--width", "1e3"], "--width: expected a whole number of pixels"),
    (["--out", "v1.txt"], "--out: expected an image file name ending in .png"),
    (["--out", "v1"], "--out: expected an image file name ending in .png"),
    (["--out", "pictures/"], "--out: expected an image file name"),
])
def test_bad_image_options_exit_2_before_loading_anything(args: list[str],
                                                          fragment: str) -> None:
    result = run_cli("show", "v1", *args)
    print(result.stderr)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.strip() == f"cramlite show: error: argument {fragment}" or \
        fragment in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_image_bounds_and_unwritable_places(tmp_path: Path) -> None:
    small = tmp_path / "deep" / "er" / "v1.jpg"
    result = run_cli("show", "v1", "--out", str(small), "--width", "1", "--height", "4096")
    assert result.returncode == 0, result.stderr
    assert Image.open(small).size == (1, 4096)
    blocker = tmp_path / "file"
    blocker.write_text("")
    under_file = run_cli("show", "v1", "--out", str(blocker / "v1.png"))
    print(under_file.stderr)
    assert under_file.returncode == 2 and "--out" in under_file.stderr
    # (as `run --image` says it, before anything is drawn)
    assert f"is under a file ({blocker}); expected a file in a folder" in under_file.stderr
    top = run_cli("show", "v1", "--top", "--width", "1", "--height", "1", "--out",
                  str(tmp_path / "tiny.png"))  # (no matplotlib warning on stderr)
    assert top.returncode == 0 and top.stderr == "", top.stderr
    folder = tmp_path / "folder.png"
    folder.mkdir()
    onto_folder = run_cli("show", "v1", "--out", str(folder))
    assert onto_folder.returncode == 2 and "is a folder" in onto_folder.stderr
    assert "Traceback" not in under_file.stderr + onto_folder.stderr


def test_show_warns_of_an_item_out_of_reach_naming_it_and_how_far(tmp_path) -> None:
    """(#27: an item at x = 1.82 passed `show` and failed at run time with "1080 base
    poses ... inside fixed geometry".)"""
    from tests.conftest import ROOT

    text = (ROOT / "worlds" / "setups" / "v1.yaml").read_text()
    far = tmp_path / "far.yaml"
    far.write_text(text.replace("pose: [1.45, 0.35, 0.85, 0.0]", "pose: [1.82, 0.35, 0.85, 0.0]"))
    result = run_cli("show", str(far), "--out", str(tmp_path / "far.png"))
    assert result.returncode == 0, result.stderr  # (valid: a run fails there, as a result)
    assert "items[0].pose: item 'spoon' at (1.82, 0.35) is out of the robot's reach: the " \
           "nearest floor the base can stand on is 0.95 m from it" in result.stderr
    assert "0.21 m nearer the open floor" in result.stderr
    unreachable = run_cli("show", "unreachable", "--out", str(tmp_path / "u.png"))
    assert "item 'milk'" in unreachable.stderr and "out of the robot's reach" in unreachable.stderr
    assert "warning" not in run_cli("show", "c3", "--out", str(tmp_path / "c3.png")).stderr
