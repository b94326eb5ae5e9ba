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
    ("actions", "[1]", "actions: a node '1' is not an object"),
    ("actions", '[{"name": "X", "start_s": 1, "end_s": 2}]', "actions: a node without"),
    ("actions", '[{"name": "X", "status": "ok", "start_s": "a", "end_s": 2}]',
     "start_s/end_s not numbers"),
    ("actions", '[{"name": "X", "status": "ok", "start_s": 1, "end_s": 2, "children": 5}]',
     "children '5' is not a list"),
])
def test_report_names_a_tampered_row(results, tmp_path, column, value, expected) -> None:
    out = _tampered(results, tmp_path, column, value)
    _one_line(run_cli("report", str(out)), "trials.csv", "line 2", expected)


@pytest.mark.parametrize("column, value, expected", [
    ("error", "x" * 200_000, "field limit"), ("trial", "\u00b2", "trial: expected"),
    ("success", "maybe", "success: expected"), ("backend", "kine\x00matic", "NUL"),
    ("items", "{not json", "items: expected a JSON dict"),
    ("actions", "[1]", "actions: a node '1' is not an object")])
def test_a_resumed_bench_names_an_unreadable_row(results, tmp_path, column, value,
                                                 expected) -> None:
    """(Before any trial runs: a file the report would refuse at the end is refused
    first.)"""
    out = _tampered(results, tmp_path, column, value)
    done = run_cli(*BENCH[:-2], "--trials", "2", "--backend", "kinematic", "--out", str(out))
    _one_line(done, "trials.csv", "line 2", expected)
    assert "1 trials" not in done.stdout + done.stderr  # (refused before running any)
    assert (out / "trials.csv").read_bytes().count(b"\nv1,") == 1


def _csv_rows(out: Path) -> list[dict[str, str]]:
    return list(csv.DictReader((out / "trials.csv").open(newline="")))


def test_a_row_copied_twice_counts_once(results, tmp_path) -> None:
    out = _tampered(results, tmp_path, "error", "")
    text = (out / "trials.csv").read_text()
    (out / "trials.csv").write_text(text + text.splitlines(keepends=True)[1])  # (row 1 again)
    assert len(_csv_rows(out)) == 2
    done = run_cli(*BENCH, "--out", str(out), "--no-plots")  # (resumed: nothing to run)
    assert done.returncode == 0, done.stderr
    summary = list(csv.DictReader((out / "summary.csv").open(newline="")))
    assert [row["trials"] for row in summary] == ["1"]
    assert "1 trial in trials.csv" in (out / "report.html").read_text()


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


def test_a_full_disk_stops_the_bench_in_one_line_and_the_next_run_resumes(
        results, tmp_path) -> None:
    import resource
    import subprocess
    import sys

    from tests.conftest import ROOT

    out = _tampered(results, tmp_path, "error", "")
    room = (out / "trials.csv").stat().st_size + 1024  # (not a second whole row)

    def full_disk() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (room, room))

    done = subprocess.run([sys.executable, "-m", "cramlite", *BENCH[:-2], "--trials", "2",
                           "--backend", "kinematic", "--workers", "1", "--no-plots",
                           "--out", str(out)], capture_output=True, text=True, cwd=ROOT,
                          timeout=300, preexec_fn=full_disk)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "Traceback" not in done.stderr
    assert "trials.csv: cannot write a trial's row (" in done.stderr.splitlines()[-1]
    again = run_cli(*BENCH[:-2], "--trials", "2", "--backend", "kinematic", "--no-plots",
                    "--out", str(out))  # (room again: the cut row is repaired, resumed)
    assert again.returncode == 0, again.stderr[-2000:]
    assert len(_csv_rows(out)) == 2


def test_a_results_file_saved_with_a_byte_order_mark_is_read(results, tmp_path) -> None:
    """(As a spreadsheet saves a CSV: the mark is not part of the first column's name.)"""
    out = _tampered(results, tmp_path, "error", "")
    (out / "trials.csv").write_bytes(b"\xef\xbb\xbf" + (out / "trials.csv").read_bytes())
    assert run_cli("report", str(out), "--no-plots").returncode == 0
    done = run_cli(*BENCH[:-2], "--trials", "2", "--backend", "kinematic", "--no-plots",
                   "--out", str(out))
    assert done.returncode == 0, done.stderr[-2000:]
    assert "(1 already in" in done.stderr


@pytest.mark.parametrize("metadata", [None, b""])
def test_a_folder_whose_metadata_is_missing_is_refused_saying_so(results, tmp_path,
                                                                 metadata) -> None:
    out = _tampered(results, tmp_path, "error", "")
    if metadata is None:
        (out / "metadata.json").unlink()
    else:
        (out / "metadata.json").write_bytes(metadata)
    _one_line(run_cli(*BENCH, "--out", str(out)), "has a trials.csv but no metadata.json")


@pytest.mark.parametrize("metadata, expected", [
    (b"{bad", "metadata.json: not valid JSON"),
    (b"[1]", "metadata.json holds a JSON list"),
])
def test_a_bench_into_a_folder_whose_metadata_is_not_a_json_object_names_it(
        results, tmp_path, metadata, expected) -> None:
    """(It was read as results of format 1, "written by an earlier cramlite".)"""
    out = _tampered(results, tmp_path, "error", "")
    (out / "metadata.json").write_bytes(metadata)
    done = run_cli(*BENCH, "--out", str(out))
    _one_line(done, expected)
    assert "format 1" not in done.stderr


@pytest.mark.parametrize("field", ["arguments", "versions"])
def test_a_report_of_metadata_with_a_field_of_the_wrong_kind_names_it(results, tmp_path,
                                                                      field) -> None:
    import json

    out = _tampered(results, tmp_path, "error", "")
    data = json.loads((out / "metadata.json").read_text())
    data[field] = "x"
    (out / "metadata.json").write_text(json.dumps(data))
    _one_line(run_cli("report", str(out)), "metadata.json", f"{field}: a JSON str, not an "
                                                            "object")
