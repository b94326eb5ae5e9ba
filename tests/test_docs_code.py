"""Every code block in the README and docs/ runs as printed (#27): the Python blocks as
scripts, the README's tour in one empty folder, in order (its `reproduce` in
test_reproduce, on a tiny subset),
the tutorial's shell commands in a scratch folder holding a copy of examples/
(`pip install` and the plugin's names apart: installing into the test environment would
leak into other tests; test_user_plans installs the plugin package into its own folder and
runs those commands)."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PLUGIN_NAMES = ("fetch-two", "farthest-first")


def _blocks(path: Path, language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", path.read_text(), re.S | re.M)


PYTHON = [(p.name, i, block) for p in DOCS for i, block in enumerate(_blocks(p, "python"))]


@pytest.mark.parametrize("doc, index, block", PYTHON, ids=[f"{d}-{i}" for d, i, _ in PYTHON])
def test_a_python_block_of_the_docs_runs(tmp_path: Path, doc: str, index: int,
                                         block: str) -> None:
    script = tmp_path / "block.py"
    script.write_text(block)
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                            cwd=tmp_path, timeout=600)
    assert result.returncode == 0, f"{doc} block {index}:\n{result.stderr[-3000:]}"


def _commands(block: str) -> list[list[str]]:
    joined = re.sub(r"\\\n\s*", " ", block)
    out = []
    for line in joined.splitlines():
        line = line.split("  #")[0].strip()
        if line and not line.startswith("#"):
            out.append(shlex.split(line))
    return out


TUTORIAL = [c for block in _blocks(ROOT / "docs" / "tutorial.md", "sh")
            for c in _commands(block)]


def test_the_tutorial_has_commands_to_run() -> None:
    assert len(TUTORIAL) >= 6 and all(c[0] in ("cramlite", "pip") for c in TUTORIAL)


@pytest.mark.parametrize("command", [c for c in TUTORIAL if c[0] == "cramlite" and not any(
    n in c for n in PLUGIN_NAMES)], ids=lambda c: " ".join(c[1:4]))
def test_a_tutorial_command_works_as_written(tmp_path: Path, command: list[str]) -> None:
    shutil.copytree(ROOT / "examples", tmp_path / "examples",
                    ignore=shutil.ignore_patterns("*.egg-info", "build", "__pycache__"))
    result = subprocess.run([sys.executable, "-m", "cramlite", *command[1:]],
                            capture_output=True, text=True, cwd=tmp_path, timeout=900)
    assert result.returncode == 0, f"{' '.join(command)}:\n{result.stderr[-3000:]}"


README_TOUR = [c for block in _blocks(ROOT / "README.md", "sh") for c in _commands(block)
               if c[0] == "cramlite"]
#: The tour's `reproduce` (a benchmark of 3 minutes) runs in test_reproduce, as printed
#: but on a tiny subset, and the checks of its page are made there.
README_REPRODUCE = next(c for c in README_TOUR if c[1] == "reproduce")


def test_the_readme_tour_runs_as_written(tmp_path: Path) -> None:
    """The five-minute tour, in order, in one empty folder (each step uses the files of
    the ones before it): every command ends with exit 0 and leaves what it promises."""
    assert [c[1] for c in README_TOUR][:3] == ["show", "run", "replay"]
    for command in README_TOUR:
        if command is README_REPRODUCE:
            continue
        result = subprocess.run([sys.executable, "-m", "cramlite", *command[1:]],
                                capture_output=True, text=True, cwd=tmp_path, timeout=900)
        assert result.returncode == 0, f"{' '.join(command)}:\n{result.stderr[-3000:]}"
        if "--out" in command:
            out = tmp_path / command[command.index("--out") + 1]
            assert out.exists() and (out.is_dir() or out.stat().st_size > 0), command
    assert "nothing penetrating" in subprocess.run(
        [sys.executable, "-m", "cramlite", "replay", "v1.jsonl", "--check"],
        capture_output=True, text=True, cwd=tmp_path).stdout
    assert (tmp_path / "tour" / "report.html").exists()
    assert (tmp_path / "two" / "report.html").exists()
    assert not (tmp_path / "results").exists()  # (`make run`'s folder: the tour keeps out)
