"""Files that are not regular files, or are too large, are one line (exit 2) before
anything reads them: a FIFO would block forever, /dev/zero would fill the memory."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from cramlite.resources import resolve_data_path
from tests.conftest import ROOT, run_cli

needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")


def _one_line(result, *expected: str) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    for text in expected:
        assert text in lines[0], lines[0]
    return lines[0]


@needs_fifo
def test_fifos_and_devices_are_refused_wherever_a_file_is_read(tmp_path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")
    _one_line(run_cli("evaluate", str(fifo), timeout=30), "is a FIFO", "regular data file")
    _one_line(run_cli("fit", str(zero), "--out", str(tmp_path / "f"), timeout=30),
              "is a character device")
    _one_line(run_cli("replay", str(fifo), "--check", timeout=30), "regular trace file")
    _one_line(run_cli("order", str(fifo), timeout=30), "regular request file")
    results = tmp_path / "results"
    results.mkdir()
    (results / "trials.csv").symlink_to("/dev/zero")
    _one_line(run_cli("report", str(results), timeout=30), "trials.csv",
              "regular results file")


def test_size_limits_name_the_file_and_how_to_raise_them(tmp_path) -> None:
    big = tmp_path / "big.csv"
    shutil.copy(resolve_data_path("table-setting"), big)
    env = {**os.environ, "CRAMLITE_MAX_FILE_MB": "0.01"}
    import subprocess
    import sys

    def cli(*args: str):
        return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                              text=True, cwd=ROOT, env=env, timeout=60)

    _one_line(cli("evaluate", str(big)), str(big), "over the 0.01 MB limit",
              "CRAMLITE_MAX_FILE_MB")
    bad = {**env, "CRAMLITE_MAX_FILE_MB": "lots"}
    result = subprocess.run([sys.executable, "-m", "cramlite", "evaluate", str(big)],
                            capture_output=True, text=True, cwd=ROOT, env=bad, timeout=60)
    _one_line(result, "CRAMLITE_MAX_FILE_MB: expected a number of megabytes")


def test_a_csv_with_a_byte_order_mark_is_read(tmp_path: Path) -> None:
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + resolve_data_path("cooking").read_bytes())
    result = run_cli("evaluate", str(path), "--repeats", "2")
    assert result.returncode == 0, result.stderr
    assert "on 123 episodes" in result.stdout


def test_a_model_archive_entry_over_the_limit_is_refused_before_extraction(tmp_path) -> None:
    import json
    import zipfile

    path = tmp_path / "bomb.model"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("model.json", json.dumps({"format": "cramlite-model"}))
        with archive.open("weights.npz", "w", force_zip64=True) as handle:
            block = bytes(2**20)
            for _ in range(520):  # 520 MB of zeros, about 0.5 MB on disk
                handle.write(block)
    assert path.stat().st_size < 2 * 2**20
    line = _one_line(run_cli("evaluate", "cooking", "--strategy", f"learned:{path}"),
                     "weights.npz", "over the 512 MB limit for a model entry file")
    assert str(path) in line
