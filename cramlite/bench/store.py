"""The results folder: trials.csv (appended row by row), metadata.json beside it.

Rows are written and flushed as trials finish, so an interrupted batch loses nothing;
a rerun with the same folder skips the trials already there (resume). A trial is
identified by its setup's name *and content hash*, plan, strategy, given order, index
and batch seed; a folder that holds another setup under the same name, or was written
with other columns, is refused rather than mixed. A line cut short by a kill is dropped
on reading.
"""

from __future__ import annotations

import csv
import io
import json
import platform
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any

COLUMNS = ["setup", "setup_hash", "plan", "strategy", "given_order", "trial", "seed",
           "batch_seed", "success", "order", "failures", "failure_types", "base_path_m",
           "straight_line_m", "wall_s", "drive_s", "arm_s", "open_close_s", "robot_time_s",
           "items", "actions", "driven_path", "error_type", "error", "worker"]
#: Columns that measure time or place, and so differ between identical runs.
TIMING_COLUMNS = ("wall_s", "robot_time_s", "worker")
KEY_COLUMNS = ("setup", "setup_hash", "plan", "strategy", "given_order", "trial",
               "batch_seed")


class StoreMismatch(Exception):
    """The folder holds results that cannot be mixed with this batch's."""


def row_key(row: dict[str, Any]) -> tuple[str, ...]:
    return tuple(str(row[c]) for c in KEY_COLUMNS)


class TrialStore:
    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path = self.folder / "trials.csv"

    def rows(self) -> list[dict[str, str]]:
        if not self.path.exists():
            return []
        text = self.path.read_text()
        rows = []
        for row in csv.DictReader(io.StringIO(text)):
            if None in row or any(row.get(c) is None for c in COLUMNS):
                continue  # a line cut short by a kill
            rows.append(row)
        return rows

    def done_keys(self) -> set[tuple[str, ...]]:
        return {row_key(r) for r in self.rows()}

    def check_compatible(self, setup_hashes: dict[str, str]) -> None:
        """Raise StoreMismatch if the file has other columns, or holds a setup of the same
        name with other content (setup name -> this batch's content hash)."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        with self.path.open(newline="") as handle:
            header = next(csv.reader(handle), [])
        if header != COLUMNS:
            raise StoreMismatch(f"{self.path} has other columns (written by another cramlite "
                                "version); expected a new folder or one written by this "
                                "version")
        for row in self.rows():
            expected = setup_hashes.get(row["setup"])
            if expected is not None and row["setup_hash"] != expected:
                raise StoreMismatch(
                    f"{self.path} holds trials of another setup named {row['setup']!r} "
                    f"(content hash {row['setup_hash']}, this one's is {expected}); expected "
                    "a new --out folder for a changed setup")

    def repair(self) -> None:
        """Rewrite the file without a trailing partial line (after a hard kill)."""
        if not self.path.exists():
            return
        text = self.path.read_text()
        if text and not text.endswith("\n"):
            self.path.write_text(text[: text.rfind("\n") + 1])

    def append(self, row: dict[str, Any]) -> None:
        new = not self.path.exists() or self.path.stat().st_size == 0
        with self.path.open("a", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=COLUMNS, extrasaction="ignore")
            if new:
                writer.writeheader()
            writer.writerow(row)
            handle.flush()

    def write_metadata(self, args: dict[str, Any], executor: str) -> None:
        versions = {}
        for package in ("cramlite", "pybullet", "pin", "ompl", "numpy", "scipy",
                        "example-robot-data", "dask", "distributed"):
            try:
                versions[package] = metadata.version(package)
            except metadata.PackageNotFoundError:
                continue
        data = {"written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "python": sys.version,
                "platform": platform.platform(), "host": platform.node(), "executor": executor,
                "versions": versions, "arguments": args}
        runs = []
        meta = self.folder / "metadata.json"
        if meta.exists():
            try:
                runs = json.loads(meta.read_text()).get("runs", [])
            except (json.JSONDecodeError, AttributeError):
                runs = []
        (self.folder / "metadata.json").write_text(json.dumps({**data, "runs": runs + [data]},
                                                              indent=2))
