from __future__ import annotations

from pathlib import Path

import numpy as np
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
