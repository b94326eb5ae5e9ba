"""The Python examples of the README and the docs run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


@pytest.mark.parametrize("page", [p for p in PAGES if _python_blocks(p)],
                         ids=lambda p: p.name)
def test_python_examples_run(page: Path, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for k, code in enumerate(_python_blocks(page)):
        namespace: dict = {}
        exec(compile(code, f"{page.name} (example {k + 1})", "exec"), namespace)


def test_the_readme_example_moves_the_cup_to_its_target(capsys) -> None:
    code = _python_blocks(ROOT / "README.md")[0]
    exec(compile(code, "README.md", "exec"), {})
    printed = capsys.readouterr().out
    x, y, _ = eval(printed.strip())
    assert abs(x + 1.0) < 0.05 and abs(y - 1.1) < 0.05
