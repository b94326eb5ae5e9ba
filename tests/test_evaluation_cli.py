"""Bad input to the evaluation commands: exit 2 and one line naming file, field, expectation."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, run_cli
from tests.test_evaluation_data import CLEANING, HEADER

#: (file name, how to make the file from a good row, text the one-line error must hold)
BAD_FILES = [
    ("nan.csv", lambda r: [*r[:2], r[2].replace("(0,0,1)", "(nan,0,1)", 1), *r[3:]],
     "row k01: coordinates: expected finite numbers"),
    ("inf.csv", lambda r: [*r[:3], r[3].replace("[2,0,1]", "[2,inf,1]", 1), *r[4:]],
     "row k01: start_coordinates: expected finite numbers"),
    ("huge.csv", lambda r: [r[0], r[1] + ",cup" * 40_000, *r[2:]],
     "line 2: a field is longer than 128 KiB"),
    ("latin1.csv", None, "line 2: expected UTF-8 text, got byte 0xe9"),
]


def write_bad(tmp_path: Path, name: str, change) -> Path:
    path = tmp_path / name
    if change is None:
        path.write_bytes(",".join(HEADER).encode() + b"\nk01,caf\xe9,x,y,0,0,0,0,0\n")
        return path
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(HEADER)
        writer.writerow(change(list(CLEANING)))
    return path


COMMAND_ARGS = {"evaluate": [], "fit": ["--out", "{tmp}/out"],
                "train": ["--model", "cpt", "--out", "{tmp}/m.model"],
                "compare": ["--strategies", "opm,nearest"]}


@pytest.mark.parametrize("command", list(COMMAND_ARGS))
@pytest.mark.parametrize(("name", "change", "expected"), BAD_FILES,
                         ids=[b[0] for b in BAD_FILES])
def test_bad_data_files_exit_2_with_one_line(tmp_path, command, name, change,
                                             expected) -> None:
    path = write_bad(tmp_path, name, change)
    extra = [a.format(tmp=tmp_path) for a in COMMAND_ARGS[command]]
    result = run_cli(command, str(path), *extra)
    print(result.stderr)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert str(path) in lines[0] and expected in lines[0]


@pytest.mark.parametrize("command", ["fit", "compare"])
def test_out_path_that_is_a_file_is_refused(tmp_path, command) -> None:
    target = tmp_path / "results"
    target.write_text("not a folder")
    extra = ["--strategies", "opm,nearest"] if command == "compare" else []
    result = run_cli(command, "table-setting", *extra, "--out", str(target))
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1
    assert f"{target}: --out: expected a folder" in result.stderr


def test_evaluate_json_into_a_closed_pipe_ends_quietly() -> None:
    code = (f"{sys.executable} -m cramlite evaluate table-setting --json | head -c 20 "
            f">/dev/null; echo \"status ${{PIPESTATUS[0]}}\"")
    done = subprocess.run(["bash", "-c", code], capture_output=True, text=True, cwd=ROOT,
                          timeout=120)
    assert "status 0" in done.stdout
    assert done.stderr == "", done.stderr


def test_protocol_option_is_offered_and_checked() -> None:
    assert "--protocol" in run_cli("evaluate", "--help").stdout
    bad = run_cli("evaluate", "table-setting", "--protocol", "published")
    assert bad.returncode == 2 and "--protocol" in bad.stderr
    ok = run_cli("evaluate", "table-setting", "--protocol", "reference", "--metric", "edit",
                 "--params", "c=1.4", "--json")
    assert ok.returncode == 0, ok.stderr
    assert '"protocol": "reference"' in ok.stdout


@pytest.mark.parametrize("args, option", [
    (["fit", "table-setting", "--out", "{file}/sub"], "--out"),
    (["compare", "table-setting", "--strategies", "opm,nearest", "--out", "{file}/sub"],
     "--out"),
    (["train", "table-setting", "--model", "cpt", "--out", "{file}/m.model"], "--out"),
    (["train", "table-setting", "--model", "cpt", "--out", "{folder}"], "--out"),
    (["fit", "table-setting", "--dims", ","], "--dims"),
])
def test_outputs_that_cannot_be_written_are_refused_before_the_work(tmp_path, args,
                                                                    option) -> None:
    afile, folder = tmp_path / "a.txt", tmp_path / "f"
    afile.write_text("a file")
    folder.mkdir()
    args = [a.format(file=afile, folder=folder) for a in args]
    result = run_cli(*args)
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert f"{option}:" in result.stderr


def test_compare_refuses_a_strategy_named_twice() -> None:
    result = run_cli("compare", "table-setting", "--strategies", "opm,nearest,opm")
    assert result.returncode == 2 and "--strategies: opm named twice" in result.stderr


def test_evaluate_prints_its_summary_and_the_episodes_only_when_asked() -> None:
    short = run_cli("evaluate", "table-setting")
    assert short.returncode == 0, short.stderr
    lines = short.stdout.strip().splitlines()
    assert len(lines) <= 6 and lines[0].startswith("opm (xy, power")
    full = run_cli("evaluate", "table-setting", "--verbose")
    assert len(full.stdout.strip().splitlines()) >= 186 + 4


def test_a_misspelt_data_set_lists_the_shipped_ones() -> None:
    done = run_cli("evaluate", "table-setings")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "table-setings: no such file; expected a CSV file of recorded sequences or a " \
           "shipped set: table-setting, cooking, clearing-up, all" in done.stderr, done.stderr


@pytest.mark.parametrize(("name", "episodes", "activity"), [
    ("cooking", 123, "cooking"), ("clearing-up", 17, "cleaning up"), ("all", 326, None)])
def test_the_shipped_subsets_load_by_name(name: str, episodes: int, activity) -> None:
    done = run_cli("evaluate", name, "--protocol", "thesis", "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["episodes"] == episodes
    if activity:
        assert list(report["by_activity"]) == [activity]
    else:
        assert set(report["by_activity"]) == {"table setting", "cooking", "cleaning up"}
    if name == "cooking":  # (the thesis: OPM 2.78 on cooking)
        assert report["mean"] == pytest.approx(2.78, abs=0.1)
