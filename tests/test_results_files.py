"""Results files that survive kills and hostile names: trials.csv cut anywhere (a cell
holding newlines included) resumes to exactly the planned rows; file names made from
user data stay in their folder and never collide."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from pathlib import Path

import pytest

from cramlite.bench.row_check import MEASURE_COLUMNS
from cramlite.bench.specs import BatchPlan, SetupEntry, trace_file
from cramlite.bench.store import COLUMNS, TrialStore
from cramlite.errors import UserInputError
from cramlite.safe_names import inside, safe_stem, trial_stem
from tests.conftest import ROOT


def row(trial: int, error: str = "") -> dict[str, str]:
    out = dict.fromkeys(COLUMNS, "x")
    out.update(trial=str(trial), error=error, setup="v1", strategy="boom", seed="7",
               batch_seed="0", success="False", carry="1", **dict.fromkeys(MEASURE_COLUMNS, ""))
    return out


MULTILINE = ('Traceback (most recent call last):\n  File "p.py", line 3\n    "quoted", cell\n'
             "ValueError: é")


def test_a_row_cut_at_any_byte_is_dropped_whole_and_resume_restores_every_row(
        tmp_path: Path) -> None:
    reference = TrialStore(tmp_path / "reference")
    for trial in range(3):
        reference.append(row(trial, MULTILINE if trial == 1 else ""))
    data = reference.path.read_bytes()
    records = list(csv.reader(io.StringIO(data.decode(), newline="")))
    assert records[2][COLUMNS.index("error")] == MULTILINE
    # the bytes of the row with the multi-line cell (after the header and the first row)
    second_start = len((csv_header() + csv_line(row(0))).encode())
    second_end = second_start + len(csv_line(row(1, MULTILINE)).encode())
    assert data[second_start:second_end] == csv_line(row(1, MULTILINE)).encode()
    for cut in range(second_start, second_end):
        store = TrialStore(tmp_path / f"cut{cut}")
        store.path.write_bytes(data[:cut])
        store.repair()
        assert store.path.read_bytes() == data[:second_start], cut
        assert [r["trial"] for r in store.rows()] == ["0"]
        store.append(row(1, MULTILINE))  # resume: the lost trial again, then the rest
        store.append(row(2))
        assert store.rows() == reference.rows(), cut
        assert store.path.read_bytes() == data


def csv_header() -> str:
    buffer = io.StringIO()
    csv.DictWriter(buffer, fieldnames=COLUMNS).writeheader()
    return buffer.getvalue()


def csv_line(values: dict[str, str]) -> str:
    buffer = io.StringIO()
    csv.DictWriter(buffer, fieldnames=COLUMNS).writerow(values)
    return buffer.getvalue()


def test_a_cut_inside_a_multibyte_character_or_the_header_is_repaired(tmp_path: Path) -> None:
    store = TrialStore(tmp_path)
    store.append(row(0, "é" * 3))
    data = store.path.read_bytes()
    store.path.write_bytes(data[:-5])  # inside the é's
    store.repair()
    header = data[: data.index(b"\r\n") + 2]
    assert store.path.read_bytes() == header and store.rows() == []
    store.path.write_bytes(header[:10])  # a header cut short
    store.repair()
    assert store.path.read_bytes() == b"" and store.rows() == []


def test_rows_are_written_in_one_call_each(tmp_path: Path, monkeypatch) -> None:
    import os

    calls = []
    real = os.write
    monkeypatch.setattr(os, "write", lambda fd, data: calls.append(data) or real(fd, data))
    store = TrialStore(tmp_path)
    store.append(row(0, MULTILINE))
    store.append(row(1))
    assert len(calls) == 2 and calls[0].count(b"\r\n") == 2  # header and row: one write


def test_resume_after_a_cut_inside_a_multiline_error_cell(tmp_path: Path) -> None:
    """The red-team case: a plugin's exception text (newlines) cut mid-row, then resume:
    every planned trial is there once, and nothing malformed stays."""
    plugin = tmp_path / "plugin"
    plugin.mkdir()
    (plugin / "multiline.py").write_text(
        "from cramlite.strategies import Strategy\n"
        "class Boom(Strategy):\n"
        "    name = 'boom'\n"
        "    def choose(self, remaining, agent):\n"
        "        raise RuntimeError('line one\\nline two, \"quoted\"\\nline three')\n")
    out = tmp_path / "out"
    args = [sys.executable, "-m", "cramlite", "bench", "--out", str(out), "--setups", "v1",
            "--strategies", "baseline,multiline:Boom", "--trials", "3", "--workers", "2",
            "--no-plots"]
    env = {"PYTHONPATH": f"{plugin}:{ROOT}", "PATH": "/usr/bin:/bin"}
    first = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, env=env,
                           timeout=600)
    assert first.returncode == 1, first.stderr
    path = out / "trials.csv"
    data = path.read_bytes()
    assert data.count(b"line two") == 3
    cut = data.index(b"line two") + 3  # inside the first multi-line cell
    path.write_bytes(data[:cut])
    again = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, env=env,
                           timeout=600)
    assert again.returncode == 1, again.stderr
    with path.open(newline="") as handle:
        records = list(csv.reader(handle))
    assert all(len(r) == len(COLUMNS) for r in records)
    keys = sorted((r[COLUMNS.index("strategy")], r[COLUMNS.index("trial")])
                  for r in records[1:])
    assert keys == sorted((s, str(t)) for s in ("baseline", "multiline:Boom")
                          for t in range(3))
    assert "3 of 6 trials failed" in again.stdout + again.stderr


@pytest.mark.parametrize("name", ["learned:../../../nn.model", "../../etc/passwd", "/abs/x",
                                  "..", ".", "a/b\\c", "\x00\n", "ü" * 200, ""])
def test_names_from_user_data_stay_inside_the_folder(tmp_path: Path, name: str) -> None:
    stem = safe_stem(name)
    path = inside(tmp_path, stem + ".png")
    assert path.parent == tmp_path and "/" not in stem and not stem.startswith(".")
    assert len(stem) <= 70
    assert Path(trace_file(tmp_path, "v1", "set-table", name, 0)).parent == tmp_path


def test_names_that_slug_alike_do_not_share_a_file() -> None:
    a = trial_stem("v1", "set-table", "learned:a/nn.model", 0)
    b = trial_stem("v1", "set-table", "learned:b/nn.model", 0)
    c = trial_stem("c1", "set-table", "learned:a/nn.model", 0)
    assert len({a, b, c}) == 3
    assert a.startswith("v1-set-table-learned_a_nn.model-0-")


def test_inside_refuses_a_name_that_leaves_the_folder(tmp_path: Path) -> None:
    with pytest.raises(UserInputError, match="would leave its folder"):
        inside(tmp_path, "../escaped.png")
    with pytest.raises(UserInputError):
        inside(tmp_path, "/etc/passwd")


def test_a_bench_plan_writes_every_trace_in_its_folder_under_its_own_name(
        tmp_path: Path) -> None:
    plan = BatchPlan({"v1": SetupEntry("v1.yaml", "h", ("a", "b")),
                      "c1": SetupEntry("c1.yaml", "h", ("a", "b"))},
                     ["learned:../../../nn.model", "opm"], 2, 0,
                     trace_dir=str(tmp_path / "traces"))
    traces = [spec.trace for spec in plan]
    assert len(set(traces)) == len(traces) == 8
    assert all(Path(t).parent == tmp_path / "traces" for t in traces)


def test_report_of_hostile_strategy_names_writes_only_inside_its_folder(tmp_path: Path) -> None:
    """A trials.csv whose cells name paths outside: every file the report writes is
    inside the results folder."""
    out = tmp_path / "deep" / "er" / "results"
    result = subprocess.run([sys.executable, "-m", "cramlite", "bench", "--out", str(out),
                             "--setups", "v1", "--strategies", "opm", "--trials", "1",
                             "--no-plots"], capture_output=True, text=True, cwd=ROOT,
                            timeout=600)
    assert result.returncode == 0, result.stderr
    path = out / "trials.csv"
    with path.open(newline="") as handle:
        records = list(csv.DictReader(handle))
    records[0]["strategy"] = "../../../../elsewhere/escaped"
    records[0]["setup"] = "../../../../elsewhere/setup"
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(records)
    before = {p for p in tmp_path.rglob("*")}
    report = subprocess.run([sys.executable, "-m", "cramlite", "report", str(out)],
                            capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert report.returncode == 0, report.stderr
    new = {p for p in tmp_path.rglob("*")} - before
    assert new and all(p.is_relative_to(out) for p in new), sorted(map(str, new))
    assert not (tmp_path / "elsewhere").exists()
