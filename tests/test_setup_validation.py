"""Every bad setup ends with exit code 2 and one line naming file, field and expectation."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import run_cli


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


def _assert_user_error(result, *fragments: str) -> None:
    print(result.stderr)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0]


def test_missing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.yaml"
    _assert_user_error(run_cli("show", str(missing)), str(missing), "v1")


def test_malformed_yaml(tmp_path: Path) -> None:
    path = _write(tmp_path, "name: x\nitems: [\n  - a: b\n")
    _assert_user_error(run_cli("show", str(path)), str(path), "line", "YAML")


def test_unknown_category(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("category: mid", "category: utensil"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[4].category",
                       "'utensil'", "strong, mid, food, none")


def test_pose_with_wrong_number_of_values(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [1.45, 0.35, 0.85]"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[0].pose",
                       "expected 4 numbers [x, y, z, yaw], got 3")


def test_item_inside_another_body(tmp_path: Path, setup_text: str) -> None:
    # the spoon moved onto the milk's spot
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [1.45, -0.15, 0.85, 0.0]"))
    _assert_user_error(run_cli("show", str(path)), str(path), "items[", ".pose", "inside",
                       "free spot")


def test_item_off_its_surface(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("pose: [1.45, 0.35, 0.85, 0.0]",
                                               "pose: [0.2, 0.35, 0.85, 0.0]"))
    _assert_user_error(run_cli("show", str(path)), "items[0].pose", "not on 'counter'")


@pytest.mark.parametrize(("old", "new", "field"), [
    ("baseline_order: [breakfast-cereal, cup, bowl, spoon, milk]",
     "baseline_order: [cup, bowl, spoon, milk]", "baseline_order"),
    ("world: kitchen", "world: moonbase", "world"),
    ("type: cup ", "type: teapot ", "items[3].type"),
    ("start: [-0.5, -1.8, 1.5708]", "start: [-0.5, oops, 1.5708]", "robot.start"),
    ("surface: island", "surface: shelf", "items[1].surface"),
])
def test_other_bad_fields(tmp_path: Path, setup_text: str, old: str, new: str,
                          field: str) -> None:
    assert old in setup_text
    path = _write(tmp_path, setup_text.replace(old, new))
    _assert_user_error(run_cli("show", str(path)), str(path), field)


def test_shipped_setups_validate_and_a_copy_works(tmp_path: Path, setup_text: str) -> None:
    path = _write(tmp_path, setup_text.replace("name: v1", "name: mine"))
    out = tmp_path / "mine.png"
    result = run_cli("show", str(path), "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 10_000
