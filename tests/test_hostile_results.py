"""A results folder a user (or a crash, or an attacker) tampered with is one line (exit 2)
naming the file and line, in `report` and in a resumed `bench`; and a trial's huge
exception text is kept bounded, so it can never make its own folder unreadable (#29
findings 6-7)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from cramlite.errors import MESSAGE_LIMIT
from tests.conftest import run_cli

BENCH = ("bench", "--setups", "v1", "--strategies", "opm", "--trials", "1", "--backend",
         "kinematic")


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("results") / "out"
    assert run_cli(*BENCH, "--out", str(out)).returncode == 0
    return out


def _tampered(results: Path, tmp_path: Path, column: str, value: str) -> Path:
    out = tmp_path / "out"
    out.mkdir()
    for name in ("metadata.json",):
        (out / name).write_bytes((results / name).read_bytes())
    rows = list(csv.DictReader((results / "trials.csv").open(newline="")))
    rows[0][column] = value
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    (out / "trials.csv").write_text(buffer.getvalue())
    return out


def _one_line(result, *expected: str) -> None:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-2000:]
    for text in expected:
        assert text in lines[0], lines[0]


@pytest.mark.parametrize("column, value, expected", [
    ("error", "x" * 200_000, "field larger than field limit"),
    ("trial", "\u00b2", "trial: expected a whole number"),
    ("trial", "9" * 40, "trial: expected a whole number"),
    ("driven_path", "[[1]]", "driven_path: expected a list of [x, y, ...] points"),
    ("driven_path", "[[1, NaN]]", "driven_path: expected"),
    ("driven_path", "[\"a\"]", "driven_path: expected"),
    ("success", "maybe", "success: expected True or False, got 'maybe'"),
    ("seed", "nan", "seed: expected a whole number"),
    ("robot_time_s", "inf", "robot_time_s: expected a number >= 0"),
    ("wall_s", "-1", "wall_s: expected a number >= 0"),
    ("backend", "kine\x00matic", "backend: holds a control character"),
])
def test_report_names_a_tampered_row(results, tmp_path, column, value, expected) -> None:
    out = _tampered(results, tmp_path, column, value)
    _one_line(run_cli("report", str(out)), "trials.csv", "line 2", expected)


@pytest.mark.parametrize("column, value, expected", [
    ("error", "x" * 200_000, "field limit"), ("trial", "\u00b2", "trial: expected"),
    ("success", "maybe", "success: expected"), ("backend", "kine\x00matic", "NUL")])
def test_a_resumed_bench_names_an_unreadable_row(results, tmp_path, column, value,
                                                 expected) -> None:
    out = _tampered(results, tmp_path, column, value)
    _one_line(run_cli(*BENCH, "--out", str(out)), "trials.csv", "line 2", expected)


def test_a_trials_huge_exception_text_is_bounded_and_the_folder_stays_readable(
        tmp_path) -> None:
    (tmp_path / "loud.py").write_text(
        "from cramlite import Strategy\n\n\n"
        "class Loud(Strategy):\n"
        "    name = 'loud'\n"
        "    uses_params = False\n\n"
        "    def choose(self, remaining, agent):\n"
        "        raise RuntimeError('first line\\n' + 'x' * 1_000_000)\n")
    out = tmp_path / "out"
    bench = ("bench", "--setups", "v1", "--strategies", "./loud.py:Loud", "--trials", "1",
             "--backend", "kinematic", "--out", str(out))
    assert run_cli(*bench, cwd=tmp_path).returncode == 1  # (the trial failed: a row)
    (row,) = csv.DictReader((out / "trials.csv").open(newline=""))
    assert row["error_type"] == "StrategyCrashed" and "RuntimeError: first line" in row["error"]
    assert MESSAGE_LIMIT < len(row["error"]) < MESSAGE_LIMIT + 100
    assert "more characters" in row["error"]
    assert run_cli(*bench, cwd=tmp_path).returncode == 1  # resumed: read back, not rerun
    assert run_cli("report", str(out)).returncode == 0


def test_a_malformed_record_in_the_middle_is_refused_never_cut(results, tmp_path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "metadata.json").write_bytes((results / "metadata.json").read_bytes())
    header, row = (results / "trials.csv").read_text().splitlines()[:2]
    text = "\n".join([header, row, '"v1"x,' + row, row]) + "\n"  # (a quote, then junk)
    (out / "trials.csv").write_text(text)
    _one_line(run_cli(*BENCH, "--out", str(out)), "trials.csv", "line 3", "not a CSV record")
    assert (out / "trials.csv").read_text() == text  # (the rows after it are all kept)
