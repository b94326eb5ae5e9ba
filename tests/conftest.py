"""Shared fixtures: setups and worlds are real (PyBullet DIRECT where installed, Pinocchio)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

#: pybullet has wheels up to Python 3.11 only: where it is missing, the tests of the
#: pybullet backend are skipped (saying so) and the rest run on the kinematic backend.
HAS_PYBULLET = importlib.util.find_spec("pybullet") is not None
NO_PYBULLET = ("pybullet is not installed (it has wheels up to Python 3.11 only): the "
               "pybullet backend's tests are skipped")
needs_pybullet = pytest.mark.skipif(not HAS_PYBULLET, reason=NO_PYBULLET)


#: Modules of end-to-end tests (whole trials, benches, venvs, trained models): marked slow,
#: left out of `make test-quick` (the full suite, `make test`, runs them; CI too).
SLOW_MODULES = {"test_other_pythons", "test_backends", "test_bench", "test_storage", "test_trials",
                "test_report", "test_learning", "test_user_plans", "test_results_files",
                "test_packaging", "test_planning_scene", "test_motion_safety",
                "test_manipulation", "test_physics_check", "test_dask", "test_process_cache",
                "test_docs_code", "test_reproduce"}


#: The longest tests (a minute or more each on 2 cores), started first: with the tests
#: spread over the cores (pytest-xdist), none of them is left to run alone at the end.
LONGEST_FIRST = ("test_the_readme_tour_runs_as_written",
                 "test_the_wheel_installs_on_python_313",
                 "test_the_wheel_installs_from_wheels_only_and_runs_on_python",
                 "test_the_broadphase_misses_no_penetration",
                 "test_dask_on_a_threaded_worker", "test_all_orders_and_random_setups",
                 "test_two_simulators_agree_on_orders_success_and_where_items_settle",
                 "test_dask_local_cluster_gives_the_same_rows",
                 "test_kinematic_and_pybullet_backends_give_the_same_trials")


def pytest_collection_modifyitems(config, items) -> None:
    for item in items:
        if item.module.__name__.rsplit(".", 1)[-1] in SLOW_MODULES:
            item.add_marker(pytest.mark.slow)
    items.sort(key=lambda item: not item.name.startswith(LONGEST_FIRST))  # (stable)


def skip_module_without_pybullet() -> None:
    """Call at the top of a test module that is about the pybullet backend."""
    if not HAS_PYBULLET:
        pytest.skip(NO_PYBULLET, allow_module_level=True)


def run_cli(*args: str, stdin: str | None = None, cwd: Path | None = None,
            timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `cramlite ...` in a subprocess, as a user would."""
    return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                          text=True, input=stdin, cwd=cwd or ROOT, timeout=timeout)


@pytest.fixture
def setup_text() -> str:
    return (ROOT / "worlds" / "setups" / "v1.yaml").read_text()


def finite_difference_accelerations(positions: np.ndarray, times: np.ndarray,
                                     ) -> np.ndarray:
    """|acceleration| of each coordinate at each junction of a timed path (states x
    coordinates), from rest before its first state and to rest after its last: the finite
    differences `replay --check` measures."""
    dt = np.diff(times)
    v = np.diff(positions, axis=0) / dt[:, None]
    v = np.vstack([np.zeros((1, positions.shape[1])), v, np.zeros((1, positions.shape[1]))])
    lengths = np.concatenate([[0.0], dt, [0.0]])
    return np.abs(np.diff(v, axis=0)) / ((lengths[:-1] + lengths[1:]) / 2)[:, None]
