"""JSON nested thousands deep, or with integers of thousands of digits, is one line (exit
2) naming the file wherever cramlite reads JSON a user could have written: trace lines,
a bench's metadata.json, a model file's model.json and sequences.json (#29 finding 6)."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from cramlite.safe_json import JSONInputError, parse_json
from tests.conftest import run_cli

DEEP = "[" * 100_000 + "]" * 100_000
LONG_INT = "{\"t\": " + "9" * 5000 + "}"


@pytest.mark.parametrize("text", [DEEP, LONG_INT, "{\"a\": ", "\ud800"])
def test_parse_json_turns_every_failure_into_one_error(text: str) -> None:
    with pytest.raises(JSONInputError, match="JSON"):
        parse_json(text)


def _one_line(result, *expected: str) -> None:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-2000:]
    for text in expected:
        assert text in lines[0], lines[0]


def test_a_deep_trace_line_is_one_line(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    assert run_cli("run", "v1", "--backend", "kinematic", "--trace", str(trace)).returncode == 0
    header, *_ = trace.read_text().splitlines()
    for bad in (DEEP, LONG_INT):
        trace.write_text(header + "\n" + bad + "\n")
        _one_line(run_cli("replay", str(trace), "--check"), "t.jsonl", "line 2", "JSON")


def test_a_deep_metadata_file_is_one_line(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert run_cli("bench", "--setups", "v1", "--strategies", "opm", "--trials", "1",
                   "--backend", "kinematic", "--out", str(out)).returncode == 0
    (out / "metadata.json").write_text(DEEP)
    _one_line(run_cli("report", str(out)), "metadata.json", "nested too deeply")


def test_a_deep_model_file_is_one_line(tmp_path: Path) -> None:
    model = tmp_path / "deep.model"
    with zipfile.ZipFile(model, "w") as archive:
        archive.writestr("model.json", DEEP)
    _one_line(run_cli("evaluate", "table-setting", "--strategy", f"learned:{model}"),
              "deep.model", "nested too deeply")
