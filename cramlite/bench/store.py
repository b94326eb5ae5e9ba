"""The results folder: trials.csv (appended row by row), metadata.json beside it.

Rows are written and flushed as trials finish, so an interrupted batch loses nothing;
a rerun with the same folder skips the trials already there (resume). A trial is
identified by its setup's name *and content hash*, plan, strategy, given order, index
and batch seed; a folder that holds another setup under the same name, or was written
with other columns, is refused rather than mixed.

Each row is written with one `write` call to a file opened for appending (and synced to
disk at most once a second), so a kill or a full disk can cut only the row being written.
`repair` finds the end of the last complete CSV *record* (a cell may hold newlines, e.g. a
plugin's exception text: cutting back to the last newline would keep half a row, and the
next rows would be swallowed into its open quote) and cuts the file there.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import platform
import sys
import time
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

from cramlite.bench.row_check import (
    CellProblem,
    legs_not_reported,
    parsed_json_cells,
    row_problem,
)
from cramlite.errors import UserInputError
from cramlite.file_limits import checked_file
from cramlite.safe_json import parse_json

COLUMNS = ["setup", "setup_hash", "plan", "strategy", "code_hash", "given_order", "backend",
           "inject", "carry", "trial",
           "seed", "batch_seed", "success", "order", "failures", "failure_types", "injected",
           "base_path_m", "straight_line_m", "wall_s", "drive_s", "arm_s", "open_close_s",
           "robot_time_s", "task_time_s", "items", "actions", "driven_path", "trips", "error_type",
           "error", "worker"]
#: Columns that measure the host's time or place, and so differ between identical runs.
TIMING_COLUMNS = ("wall_s", "task_time_s", "worker")
KEY_COLUMNS = ("setup", "setup_hash", "plan", "strategy", "code_hash", "given_order",
               "backend", "trial", "batch_seed", "inject", "carry")
#: What the columns mean (DEFINITIONS: robot_time_s is the robot's own time from 2 on; in
#: 1 it was wall + driving + arm time; 3 adds code_hash, the hash of a plan file and of a
#: learned strategy's model file; 4 adds inject, the failures injected (a key column), and
#: injected, how many were drawn by kind; 5 adds carry, how many items were carried at
#: once (a key column), and trips, the items fetched together on each trip). A folder of
#: another format is not resumed into.
RESULTS_FORMAT = 5
#: Rows are synced to disk at most this often (seconds); each is written whole anyway.
SYNC_INTERVAL_S = 1.0


class StoreMismatch(Exception):
    """The folder holds results that cannot be mixed with this batch's."""


def row_key(row: dict[str, Any]) -> tuple[str, ...]:
    return tuple(str(row[c]) for c in KEY_COLUMNS)


def key_digest(key: Sequence[str]) -> str:
    """A trial's key (`TrialSpec.key`, `row_key`) as 16 hex digits: how metadata.json
    lists the trials of the last bench command (the report shows those)."""
    return hashlib.sha256("\x1f".join(key).encode()).hexdigest()[:16]


class TrialStore:
    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path = self.folder / "trials.csv"
        self._synced = -SYNC_INTERVAL_S

    def rows(self, json_checked: bool = False) -> list[dict[str, str]]:
        """The complete records (a row being written, or cut by a kill, is not one), each
        once (a row copied into the file twice counts once); `json_checked`: their JSON
        cells checked as the report reads them too (`row_check.parsed_json_cells`)."""
        if not self.path.exists():
            return []
        checked_file(self.path, "results")
        with self.path.open("rb") as handle:
            data = handle.read()
        # (utf-8-sig: a byte-order mark, as a spreadsheet saves one, is not in a column name)
        text = data[:self._records_end(data)].decode("utf-8-sig", errors="replace")
        rows: list[dict[str, str]] = []
        seen: set[tuple[str, ...]] = set()
        reader = csv.DictReader(io.StringIO(text, newline=""))
        try:
            for row in reader:
                if None in row or any(row.get(c) is None for c in COLUMNS):
                    continue  # (a record of other columns)
                problem = row_problem(row)
                if problem:
                    raise UserInputError(f"{problem[0]}: {problem[1]}", source=str(self.path),
                                         field=f"line {reader.line_num}")
                if json_checked:
                    try:
                        parsed_json_cells(row)
                    except CellProblem as exc:
                        raise UserInputError(str(exc), source=str(self.path),
                                             field=f"line {reader.line_num}") from None
                key = row_key(row)
                if key in seen:
                    continue  # (the same trial twice: the first record stands)
                seen.add(key)
                rows.append(legs_not_reported(row))
        except csv.Error as exc:  # e.g. a cell over the csv module's 128 KiB
            raise UserInputError(f"not a CSV record ({exc}); expected the rows `cramlite "
                                 "bench` writes", source=str(self.path),
                                 field=f"line {reader.line_num}") from None
        return rows

    def done_keys(self) -> set[tuple[str, ...]]:
        return {row_key(r) for r in self.rows()}

    def check_compatible(self, setup_hashes: dict[str, str]) -> None:
        """Raise StoreMismatch if the file has other columns, or holds a setup of the same
        name with other content (setup name -> this batch's content hash)."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        meta = self.folder / "metadata.json"
        if not meta.is_file() or meta.stat().st_size == 0:
            raise StoreMismatch(f"{self.folder} has a trials.csv but no metadata.json beside "
                                "it (or an empty one); expected the two files a bench writes "
                                "(restore metadata.json, or use a new --out folder)")
        found = self.results_format()
        if found != RESULTS_FORMAT:
            raise StoreMismatch(f"{self.folder} holds results of format {found} (written by "
                                "an earlier cramlite: format 1's robot_time_s included the "
                                "wall time, format 2 had no code_hash, format 3 no "
                                "inject, format 4 no carry); this cramlite writes format "
                                f"{RESULTS_FORMAT}; "
                                "expected a new --out folder (`cramlite report` still shows "
                                "the old one)")
        with self.path.open(newline="", encoding="utf-8-sig") as handle:
            header = next(csv.reader(handle), [])
        if header != COLUMNS:
            raise StoreMismatch(f"{self.path} has other columns (written by another cramlite "
                                "version); expected a new folder or one written by this "
                                "version")
        for row in self.rows(json_checked=True):
            expected = setup_hashes.get(row["setup"])
            if expected is not None and row["setup_hash"] != expected:
                raise StoreMismatch(
                    f"{self.path} holds trials of another setup named {row['setup']!r} "
                    f"(content hash {row['setup_hash']}, this one's is {expected}); expected "
                    "a new --out folder for a changed setup")

    def _records_end(self, data: bytes) -> int:
        try:
            return complete_records_end(data)
        except MalformedRecord as exc:
            raise UserInputError(f"{exc}; expected the rows `cramlite bench` writes (fix or "
                                 "remove that record)", source=str(self.path),
                                 field=f"line {exc.line}") from None

    def repair(self) -> None:
        """Cut the file after its last complete record (after a kill or a full disk)."""
        if not self.path.exists():
            return
        checked_file(self.path, "results")
        with self.path.open("rb") as handle:
            data = handle.read()
        end = self._records_end(data)
        if end < len(data):
            with self.path.open("r+b") as handle:
                handle.truncate(end)

    def append(self, row: dict[str, Any]) -> None:
        """Append one row in a single write (the header first, into an empty file)."""
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, fieldnames=COLUMNS, extrasaction="ignore")
        new = not self.path.exists() or self.path.stat().st_size == 0
        if new:
            writer.writeheader()
        writer.writerow(row)
        data = buffer.getvalue().encode("utf-8")
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
            try:
                written = os.write(fd, data)
                if written != len(data):  # (a regular file takes it whole, or fails)
                    raise OSError(28, "No space left on device", str(self.path))
                now = time.monotonic()
                if now - self._synced >= SYNC_INTERVAL_S:
                    os.fsync(fd)
                    self._synced = now
            finally:
                os.close(fd)
        except OSError as exc:  # (a full disk, a file made read-only: the batch stops)
            raise UserInputError(f"cannot write a trial's row ({exc.strerror or exc}); "
                                 "expected a writable file with room for it (the rows "
                                 "written are kept: the same command resumes once there "
                                 "is)", source=str(self.path)) from None

    def results_format(self) -> int:
        """The format of the results in the folder (1: before it was recorded). A
        metadata.json that is not a JSON object is a StoreMismatch naming it (it was read
        as format 1, which told the user of an earlier cramlite that never wrote it)."""
        meta = self.folder / "metadata.json"
        try:
            data = parse_json(meta.read_text(encoding="utf-8"))
        except OSError as exc:
            raise StoreMismatch(f"{meta} cannot be read ({exc.strerror or exc}); expected "
                                "the metadata a bench writes") from None
        except (ValueError, UnicodeDecodeError) as exc:
            raise StoreMismatch(f"{meta}: {exc}; expected the metadata a bench writes "
                                "(restore it, or use a new --out folder)") from None
        if not isinstance(data, dict):
            raise StoreMismatch(f"{meta} holds a JSON {type(data).__name__}; expected the "
                                "object of metadata a bench writes (restore it, or use a new "
                                "--out folder)")
        value = data.get("results_format", 1)
        return value if type(value) is int else 1  # (not true, which == 1)

    def write_metadata(self, args: dict[str, Any], executor: str,
                       batch: Sequence[str] = ()) -> None:
        """metadata.json: the versions, the host, this command's arguments and `batch`,
        its trials' key digests (`key_digest`), with the earlier commands' in `runs`."""
        versions = {}
        for package in ("cramlite", "pybullet", "mujoco", "pin", "coal", "ompl", "numpy",
                        "scipy", "example-robot-data", "dask", "distributed"):
            try:
                versions[package] = metadata.version(package)
            except metadata.PackageNotFoundError:
                continue
        data = {"results_format": RESULTS_FORMAT,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "python": sys.version,
                "platform": platform.platform(), "host": platform.node(), "executor": executor,
                "versions": versions, "arguments": args, "cwd": os.getcwd(),
                "batch": list(batch)}
        runs = []
        meta = self.folder / "metadata.json"
        if meta.exists():
            try:
                runs = parse_json(meta.read_text(encoding="utf-8")).get("runs", [])
            except (OSError, ValueError, AttributeError):
                runs = []
        # (the trials' digests are the last command's alone: not repeated in `runs`)
        earlier = {k: v for k, v in data.items() if k != "batch"}
        text = json.dumps({**data, "runs": runs + [earlier]}, indent=2)
        temporary = meta.with_name(meta.name + ".tmp")  # (whole or not at all)
        temporary.write_text(text)
        os.replace(temporary, meta)


class _Lines:
    """The lines of a text (each with its newline) that remember where they have got to,
    so that a CSV reader fed from them tells where each record ends."""

    def __init__(self, text: str):
        self.text = text
        self.position = 0

    def __iter__(self) -> _Lines:
        return self

    def __next__(self) -> str:
        if self.position >= len(self.text):
            raise StopIteration
        newline = self.text.find("\n", self.position)
        end = len(self.text) if newline < 0 else newline + 1
        line = self.text[self.position:end]
        self.position = end
        return line


def complete_records_end(data: bytes) -> int:
    """The byte offset just after the last complete record of a trials.csv written with
    this version's columns: a record that ends with a newline outside quotes (the last
    one must also have every column). What lies past it is a record cut anywhere (inside
    a quoted multi-line cell too). A file whose header is not this version's is left
    whole (the bench refuses it, naming it)."""
    text = data.decode("utf-8", errors="surrogateescape")  # (round-trips every byte)
    lines = _Lines(text)
    reader = csv.reader(lines, strict=True)
    end = 0
    try:
        header = next(reader)
        if not text[:lines.position].endswith("\n"):
            return 0  # (the header itself cut short)
        if header != COLUMNS:
            return len(data)
        end = lines.position
        for record in reader:
            if not text[:lines.position].endswith("\n"):
                break
            if len(record) != len(COLUMNS):
                if lines.position >= len(text):
                    break  # the last record, cut just after a newline inside a cell
                continue  # (a malformed record in the middle: kept, `rows` skips it)
            end = lines.position
    except StopIteration:
        pass
    except csv.Error as exc:
        if "field limit" in str(exc) or lines.position < len(text):
            # not a cut record (that one ends the file): a malformed one, with what follows
            # it kept (cutting there would lose every complete row after it)
            line = text.count("\n", 0, lines.position) + (not text[:lines.position]
                                                          .endswith("\n"))
            raise MalformedRecord(f"not a CSV record ({exc})", line) from None
        # (an open quote at the end: a cut cell)
    return len(text[:end].encode("utf-8", errors="surrogateescape"))


class MalformedRecord(ValueError):
    """A record of a trials.csv that no crash can have written (it is not at the end, or
    has a cell over the csv module's limit): the file is refused, never cut there."""

    def __init__(self, message: str, line: int):
        super().__init__(message)
        self.line = line
