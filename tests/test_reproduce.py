"""`cramlite reproduce` on a tiny subset: every section is rebuilt, ours beside the
published figures, and its numbers are those the commands themselves give."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cramlite.evaluation.data import load_episodes
from cramlite.evaluation.evaluate import evaluate
from cramlite.resources import resolve_data_path
from tests.conftest import run_cli


def _row(markdown: str, *starts: str) -> list[str]:
    for line in markdown.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if cells[:len(starts)] == list(starts):
            return cells
    raise AssertionError(f"no row {starts} in the page")


def test_reproduce_rebuilds_every_table_on_a_tiny_subset(tmp_path) -> None:
    """The README tour's `reproduce` as printed (run in an empty folder), on a tiny
    subset."""
    from tests.test_docs_code import README_REPRODUCE

    result = run_cli(*README_REPRODUCE[1:], "--episodes", "10", "--setups", "v1",
                     "--epochs", "2", "--recovery-sets", "2", "--recovery-seeds", "1",
                     "--repeats", "5", cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    out = tmp_path / README_REPRODUCE[README_REPRODUCE.index("--out") + 1]
    page = (out / "reproduce.md").read_text()
    assert (out / "reproduce.html").read_text().count("<table>") == 5
    for title in ("Table 3.4", "Tables 4.2-4.4", "Table 3.8", "Ablation", "Parameter recovery"):
        assert title in page
    # the robot's orders are Tables 4.2 and 4.3 (run here, not copied)
    v1 = _row(page, "v1")
    assert v1[2] == "same" and v1[4] == "same" and v1[6] == "0.4"
    # the OPM's cooking figure is what evaluate gives on the same episodes
    cooking = load_episodes(resolve_data_path("cooking"))[0][:10]
    expected = np.mean(evaluate(cooking, "opm", repeats=5, protocol="thesis").scores)
    opm = _row(page, "cooking", "10", "OPM")
    assert opm[3] == "2.78" and float(opm[4]) == pytest.approx(expected, abs=0.005)
    # the ablation's floors count the unseen items: none in table setting
    floor = _row(page, "floor: steps taking an unseen item (n-1)")
    assert floor[1] == "0.00" and float(floor[3]) > 5
    assert re.search(r"\| c \| \d+ % \| \d+ % \|", page)


def test_compare_shows_the_published_figure_beside_ours_where_comparable() -> None:
    thesis = run_cli("compare", "cooking", "--strategies", "opm,nearest", "--protocol",
                     "thesis", "--repeats", "5")
    assert thesis.returncode == 0, thesis.stderr
    assert re.search(r"opm: mean 2\.\d+ \(thesis 2\.78\)", thesis.stdout)
    assert "nearest: mean" in thesis.stdout and thesis.stdout.count("(thesis") == 1
    heldout = run_cli("compare", "cooking", "--strategies", "opm,nearest", "--repeats", "5")
    assert heldout.returncode == 0 and "(thesis" not in heldout.stdout
