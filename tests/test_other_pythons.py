"""cramlite on the Pythons beside this suite's own, as a user installs it: the wheel with
its mujoco extra, from wheels only (no compiler), into a fresh venv, then the main
commands.

- 3.13 and 3.12: no pybullet (it has no wheel there); the default backend is MuJoCo 4
  (physics settling, offscreen pictures). On 3.13 the whole tour: `run`, `replay --check`,
  `replay --out`, `bench` with its report.
- 3.10: pybullet is installed and the default; the extra gives MuJoCo 3.x (mujoco 4 needs
  3.11), whose backend runs a trial that `replay --check` finds clean.

Each version uses the python $CRAMLITE_PYTHON3XX names (e.g. CRAMLITE_PYTHON310; only it,
if set), else one from PATH or pyenv; it is skipped, saying why, where there is none.
"""

from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.conftest import ROOT

#: Per version: the default backend, whether pybullet is installed, the mujoco package.
VERSIONS = {"3.10": ("pybullet", True, "mujoco"),
            "3.12": ("mujoco", False, "mujoco-core"),
            "3.13": ("mujoco", False, "mujoco-core")}


def is_python(candidate: str, version: str) -> bool:
    """Whether `candidate` runs and is a Python of this version (e.g. "3.13")."""
    try:
        done = subprocess.run([candidate, "-c", "import sys; print(sys.version_info[:2])"],
                              capture_output=True, text=True, timeout=60)
    except OSError:
        return False
    return done.returncode == 0 and done.stdout.strip() == str(
        tuple(map(int, version.split("."))))


def find_python(version: str) -> tuple[str | None, str]:
    """An interpreter of this version (e.g. "3.13") and "", or None and why: $CRAMLITE_
    PYTHON3XX if set (only it), else python3.XX on PATH, else the newest under pyenv."""
    env = f"CRAMLITE_PYTHON{version.replace('.', '')}"
    given = os.environ.get(env)
    if given:
        return (given, "") if is_python(given, version) else (
            None, f"${env} is {given!r}, which is not a Python {version} that runs")

    def newest_first(path: str) -> tuple[int, ...]:
        patch = path.split("/versions/")[-1].split("/")[0].split(".")[2:3]
        return (-int(patch[0]) if patch and patch[0].isdigit() else 0,)

    candidates = [shutil.which(f"python{version}"),
                  *sorted(glob.glob(os.path.expanduser(
                      f"~/.pyenv/versions/{version}.*/bin/python{version}")),
                      key=newest_first)]
    for candidate in candidates:
        if candidate and is_python(candidate, version):
            return candidate, ""
    return None, (f"no Python {version} here (looked for ${env}, python{version} on PATH "
                  f"and ~/.pyenv/versions/{version}.*)")


FOUND = {version: find_python(version) for version in VERSIONS}


def _run(args: list[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    done = subprocess.run(args, capture_output=True, text=True, cwd=cwd, timeout=timeout)
    assert done.returncode == 0, f"{' '.join(args)}\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
    return done


def _venv(version: str, work: Path) -> Path:
    """A venv of this Python with the cramlite wheel and its mujoco extra, from wheels
    only (the wheel itself built by that Python)."""
    python, why = FOUND[version]
    if python is None:
        pytest.skip(f"{why}: the {version} install is not tested")
    # (from a copy of the tree: setuptools writes build/ and *.egg-info into the tree it
    # builds, and two versions' builds at once, on two test workers, would collide there)
    source = work / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "*.egg-info", "__pycache__", ".*_cache", "results"))
    _run([python, "-m", "pip", "wheel", "--quiet", "--no-deps", "--wheel-dir",
          str(work / "dist"), str(source)], cwd=work)
    (wheel,) = (work / "dist").glob("cramlite-*.whl")
    _run([python, "-m", "venv", str(work / "venv")], cwd=work)
    _run([str(work / "venv" / "bin" / "python"), "-m", "pip", "install", "--quiet",
          "--only-binary=:all:", f"{wheel}[mujoco]"], cwd=work, timeout=900)
    return work / "venv"


def _installed(venv: Path, tmp_path: Path, version: str) -> None:
    """The packages the wheel brought: pybullet only where it has wheels."""
    _, pybullet, mujoco = VERSIONS[version]
    listed = _run([str(venv / "bin" / "python"), "-m", "pip", "list", "--format=json"],
                  cwd=tmp_path)
    packages = {p["name"].lower() for p in json.loads(listed.stdout)}
    assert ("pybullet" in packages) == pybullet, sorted(packages)
    assert {"cramlite", "pin", "ompl", "coal", mujoco} <= packages, sorted(packages)


def _trial(cramlite: str, tmp_path: Path, *args: str) -> dict:
    return json.loads(_run([cramlite, "run", *args, "--json"], cwd=tmp_path).stdout)


def test_the_wheel_installs_on_python_313_with_mujoco_without_pybullet_and_runs(
        tmp_path_factory: pytest.TempPathFactory, tmp_path: Path) -> None:
    venv = _venv("3.13", tmp_path_factory.mktemp("py313"))
    _installed(venv, tmp_path, "3.13")
    cramlite = str(venv / "bin" / "cramlite")
    for setup in ("v1", "c1"):
        result = _trial(cramlite, tmp_path, setup, "--trace", f"{setup}.jsonl")
        assert result["success"] and result["backend"] == "mujoco", result
    opm = _trial(cramlite, tmp_path, "v1", "--strategy", "opm")
    assert " ".join(opm["order"]) == "bowl breakfast-cereal cup spoon milk"  # Table 4.3
    # (the check and the picture of the shorter trace: c1's 3 500 states are checked on
    # 3.11 by test_storage, and here would cost half a minute more)
    checked = _run([cramlite, "replay", "v1.jsonl", "--check"], cwd=tmp_path)
    assert "nothing penetrating" in checked.stdout, checked.stdout
    drawn = _run([cramlite, "replay", "v1.jsonl", "--out", "v1.gif", "--speed", "40"],
                 cwd=tmp_path)
    assert "drawn as the mujoco backend draws" in drawn.stdout, drawn.stdout
    assert (tmp_path / "v1.gif").stat().st_size > 10_000
    _run([cramlite, "bench", "--trials", "1", "--out", "results"], cwd=tmp_path)
    rows = (tmp_path / "results" / "trials.csv").read_text().splitlines()
    assert len(rows) == 11  # header + v1..v5 x opm, baseline
    assert (tmp_path / "results" / "report.html").is_file()


@pytest.mark.parametrize("version", ["3.12", "3.10"])
def test_the_wheel_installs_from_wheels_only_and_runs_on_python(
        version: str, tmp_path_factory: pytest.TempPathFactory, tmp_path: Path) -> None:
    """3.12 as 3.13 (MuJoCo 4 the default, no pybullet); 3.10 with pybullet the default
    and MuJoCo 3.x beside it: a trial on each, its trace checked clean."""
    venv = _venv(version, tmp_path_factory.mktemp(f"py{version.replace('.', '')}"))
    _installed(venv, tmp_path, version)
    cramlite = str(venv / "bin" / "cramlite")
    default = VERSIONS[version][0]
    result = _trial(cramlite, tmp_path, "c1")
    assert result["success"] and result["backend"] == default, result
    opm = _trial(cramlite, tmp_path, "v1", "--strategy", "opm", "--backend", "mujoco",
                 "--trace", "v1.jsonl")
    assert opm["success"] and opm["backend"] == "mujoco", opm
    assert " ".join(opm["order"]) == "bowl breakfast-cereal cup spoon milk"  # Table 4.3
    checked = _run([cramlite, "replay", "v1.jsonl", "--check"], cwd=tmp_path)
    assert "nothing penetrating" in checked.stdout, checked.stdout
    assert "nothing found" in checked.stdout, checked.stdout
