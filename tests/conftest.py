"""Shared fixtures: setups and worlds are real (PyBullet DIRECT, Pinocchio)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args: str, stdin: str | None = None, cwd: Path | None = None,
            timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `cramlite ...` in a subprocess, as a user would."""
    return subprocess.run([sys.executable, "-m", "cramlite", *args], capture_output=True,
                          text=True, input=stdin, cwd=cwd or ROOT, timeout=timeout)


@pytest.fixture
def setup_text() -> str:
    return (ROOT / "worlds" / "setups" / "v1.yaml").read_text()
