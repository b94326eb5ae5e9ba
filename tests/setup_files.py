"""Setup files built for tests: v1 with changes, and a setup with many items."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import ROOT


def v1_text() -> str:
    return (ROOT / "worlds" / "setups" / "v1.yaml").read_text()


def many_cups(count: int, name: str = "cups") -> str:
    """`count` cups (up to 16) in two rows on the counter, their targets in two rows on
    the island: a valid setup with more items than `optimal` plans for."""
    assert count <= 16
    lines = ["format: 1", f"name: {name}", "world: kitchen", "robot:",
             "  start: [-0.5, -1.8, 1.5708]", "items:"]
    names = []
    for i in range(count):
        row, col = divmod(i, 8)
        x, y = (1.40, 1.58)[row], -0.8 + 0.22 * col
        tx, ty = (-0.85, -1.05)[row], 0.6 + 0.2 * col
        names.append(f"cup-{i:02d}")
        lines += [f"  - name: cup-{i:02d}", "    type: cup", f"    pose: [{x}, {y:.2f}, 0.85, 0.0]",
                  "    surface: counter", f"    target: [{tx}, {ty:.2f}, 0.86, 0.0]"]
    lines.append(f"baseline_order: [{', '.join(names)}]")
    return "\n".join(lines) + "\n"


def write(folder: Path, text: str, name: str = "setup.yaml") -> Path:
    path = folder / name
    path.write_text(text)
    return path
