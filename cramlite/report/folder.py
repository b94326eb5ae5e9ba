"""Reading a bench results folder for the report: rows, metadata, setups, traces, status.

Works on a folder still being filled (a line cut short is left out) or interrupted, and on
folders of older versions as long as the columns the report needs are there. A folder
that is not a bench folder, holds no finished trial or has a malformed file is refused
with a `UserInputError` naming the file (and line and column) and what was expected.
"""

from __future__ import annotations

import contextlib
import csv
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cramlite.bench.labels import by_backend, several_backends, several_carries
from cramlite.bench.row_check import (
    JSON_COLUMNS,
    CellProblem,
    legs_not_reported,
    parsed_json_cells,
    row_problem,
)
from cramlite.bench.specs import FIXED_ORDER, trace_file
from cramlite.bench.store import KEY_COLUMNS, key_digest
from cramlite.errors import UserInputError
from cramlite.file_limits import checked_file
from cramlite.safe_json import JSONInputError, parse_json

#: Columns the report cannot do without; the others default to empty.
REQUIRED = ("setup", "strategy", "trial", "success", "order")
NOT_A_BENCH = "expected a results folder written by `cramlite bench --out DIR`"


@dataclass
class BenchFolder:
    """What the report shows, read from a results folder."""

    path: Path
    rows: list[dict[str, Any]]  #: trials.csv, JSON columns parsed, in file order
    metadata: dict[str, Any]
    setups: dict[str, Any]  #: setup name -> Setup (None: could not be loaded)
    setup_notes: dict[str, str] = field(default_factory=dict)
    strategies: list[str] = field(default_factory=list)  #: sorted, without fixed-order
    planned: int | None = None  #: trials the last bench command runs in all
    planned_done: int = 0  #: of them, how many are in the folder
    running: str = ""  #: who holds the folder's lock (a bench still filling it), or ""
    #: Trials in trials.csv of other bench commands than the last (not shown: other
    #: options, seeds, versions of a plan; `metadata.json` lists the last one's trials).
    other_batches: int = 0

    @property
    def backends(self) -> list[str]:
        """The backends the rows ran on (none named: rows of an older cramlite)."""
        return sorted({r.get("backend") or "" for r in self.rows})

    @property
    def setup_names(self) -> list[str]:
        return sorted(self.setups)

    def trace(self, row: dict[str, Any]) -> Path | None:
        """The trial's trace, if the bench wrote one (`bench --traces`)."""
        folder = self.path / "traces"
        backend = row.get("backend", "") if len(self.backends) > 1 else ""
        path = Path(trace_file(folder, row["setup"], row.get("plan", ""),
                               row.get("strategy_name", row["strategy"]), row["trial"],
                               backend))
        return path if path.is_file() and path.stat().st_size > 0 else None


def read_folder(path: str | Path, running: bool | None = None) -> BenchFolder:
    """Read a bench folder; `running`: whether a bench is still writing into it (None:
    find out from its lock)."""
    folder = Path(path)
    src = str(folder)
    if not folder.exists():
        raise UserInputError(f"no such folder; {NOT_A_BENCH}", source=src)
    if not folder.is_dir():
        raise UserInputError(f"is a file; {NOT_A_BENCH}", source=src)
    csv_path, meta_path = folder / "trials.csv", folder / "metadata.json"
    if not csv_path.exists() and not meta_path.exists():
        raise UserInputError(f"holds no trials.csv or metadata.json; {NOT_A_BENCH}",
                             source=src)
    metadata = _metadata(meta_path)
    every = _rows(csv_path)
    batch = metadata.get("batch")
    wanted = {str(digest) for digest in batch} if isinstance(batch, list) else set()
    # the last bench command's trials (none of them yet, or a folder of a cramlite before
    # 2026-12: every row)
    rows = [r for r in every if key_digest(_key(r)) in wanted]
    in_batch = len(rows)
    rows = rows or every
    if not rows:
        raise UserInputError("no finished trial yet; expected at least one row (rerun the "
                             "report once the bench has finished a trial)",
                             source=str(csv_path))
    rows = by_backend(rows)
    arguments = metadata.get("arguments") if isinstance(metadata.get("arguments"), dict) \
        else {}
    strategies = {r["strategy"] for r in rows}
    if not several_backends(rows) and not several_carries(rows):  # (the strategies asked
        # for, also those with no row yet)
        strategies |= set(_names(arguments.get("strategies")))
    result = BenchFolder(folder, rows, metadata, {},
                         strategies=sorted(strategies - {FIXED_ORDER}),
                         other_batches=len(every) - len(rows))
    _load_setups(result, arguments)
    if wanted:
        result.planned, result.planned_done = len(wanted), in_batch
    else:
        _planned(result, arguments)
    result.running = "" if running is False else _lock_holder(folder)
    return result


def _metadata(path: Path) -> dict[str, Any]:
    if not path.exists():
        return {}
    checked_file(path, "results")
    try:
        data = parse_json(path.read_text(encoding="utf-8"))
    except (JSONInputError, UnicodeDecodeError) as exc:
        raise UserInputError(f"{exc if isinstance(exc, JSONInputError) else 'not UTF-8'}; "
                             "expected the metadata "
                             "`cramlite bench` writes", source=str(path)) from None
    if not isinstance(data, dict):
        raise UserInputError("expected a JSON object", source=str(path))
    for key in ("arguments", "versions"):  # (what the report reads field by field)
        if key in data and not isinstance(data[key], dict):
            raise UserInputError(f"a JSON {type(data[key]).__name__}, not an object; "
                                 "expected the metadata `cramlite bench` writes",
                                 source=str(path), field=key)
    return data


def _rows(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    src = str(path)
    checked_file(path, "results")
    try:
        text = path.read_text(encoding="utf-8-sig")  # (a spreadsheet's BOM: fine)
    except UnicodeDecodeError:
        raise UserInputError("not UTF-8 text; expected the CSV `cramlite bench` writes",
                             source=src) from None
    reader = csv.DictReader(text.splitlines(keepends=True))
    header = reader.fieldnames or []
    if not header:
        return []
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise UserInputError(f"has no column {', '.join(missing)}; expected the columns "
                             "`cramlite bench` writes", source=src, field="line 1")
    rows, seen = [], set()
    try:
        for number, row in enumerate(reader, start=2):
            row = _checked_row(row, header, src, number)
            if row is not None and _key(row) not in seen:  # (a trial twice: the first)
                seen.add(_key(row))
                rows.append(legs_not_reported(row))
    except csv.Error as exc:  # e.g. a cell over the csv module's 128 KiB
        raise UserInputError(f"not a CSV record ({exc}); {NOT_A_BENCH}", source=src,
                             field=f"line {reader.line_num + 1}") from None
    return rows


def _checked_row(row: dict[str, Any], header: list[str], src: str, number: int,
                 ) -> dict[str, Any] | None:
    """A row with its JSON columns parsed and checked (None: a line cut short)."""
    if None in row or any(row.get(c) is None for c in header):
        return None  # a line cut short by a kill, or being written
    for column, kind in JSON_COLUMNS.items():
        row.setdefault(column, "[]" if kind is list else "{}")
    try:
        row.update(parsed_json_cells(row))
    except CellProblem as exc:
        raise UserInputError(str(exc), source=src, field=f"line {number}") from None
    problem = row_problem(row)
    if problem:
        raise UserInputError(f"{problem[0]}: {problem[1]}", source=src, field=f"line {number}")
    return row


def _key(row: dict[str, Any]) -> tuple[str, ...]:
    """A row's trial key, as `bench.store.row_key` (a column an older folder lacks: "")."""
    return tuple(str(row.get(c, "")) for c in KEY_COLUMNS)


def _names(text: Any) -> list[str]:
    return [p.strip() for p in str(text or "").split(",") if p.strip()]


def _load_setups(folder: BenchFolder, arguments: dict[str, Any]) -> None:
    """Each setup of the rows (and of the bench's arguments), from the folder's own
    random setups, the paths the bench was given or the shipped ones; the one whose
    content hash matches the rows."""
    from cramlite.world.setup import load_setup

    candidates: dict[str, list[Any]] = {}
    given = _names(arguments.get("setups"))
    cwd = folder.metadata.get("cwd")  # (a path the bench was given relative to its folder)
    if isinstance(cwd, str) and cwd:
        given += [str(Path(cwd) / name) for name in given if not Path(name).is_absolute()]
    sources = [str(p) for p in sorted((folder.path / "setups").glob("*.yaml"))] + given
    for source in sources:
        try:
            setup = load_setup(source)
        except UserInputError:
            continue
        candidates.setdefault(setup.name, []).append(setup)
    hashes = {r["setup"]: r.get("setup_hash", "") for r in folder.rows}
    for name in sorted(set(hashes) | set(candidates)):
        found = list(candidates.get(name, []))
        if not found:
            with contextlib.suppress(UserInputError):
                found.append(load_setup(name))
        wanted = hashes.get(name, "")
        match = next((s for s in found if not wanted or s.content_hash == wanted), None)
        if match is None and found:
            match = found[0]
            folder.setup_notes[name] = (f"the setup file changed since the bench ran (content "
                                        f"hash {match.content_hash}, the trials' is {wanted}): "
                                        "the map shows it as it is now")
        elif match is None:
            folder.setup_notes[name] = "its setup file was not found: no map"
        folder.setups[name] = match


def _planned(folder: BenchFolder, arguments: dict[str, Any]) -> None:
    """How many trials the last bench command runs, and how many of them are done."""
    try:
        trials = int(arguments["trials"])
        strategies = _names(arguments["strategies"])
    except (KeyError, TypeError, ValueError):
        return
    names = [s.name for s in folder.setups.values() if s is not None
             and (s.name in _names(arguments.get("setups")) or
                  str(s.source) in _names(arguments.get("setups")) or
                  s.source.parent == folder.path / "setups")]
    names = sorted(set(names))
    backends = _names(arguments.get("backends")) or [""]
    total = len(names) * len(strategies) * trials
    if arguments.get("all_orders"):
        total += sum(math.factorial(len(folder.setups[n].items)) for n in names)
    total *= len(backends)
    done = {(r["setup"], r["strategy"], r["trial"], r.get("given_order", ""),
             r.get("backend", "")) for r in folder.rows if r["setup"] in names
            and (r["strategy"] == FIXED_ORDER or (r["strategy_name"] in strategies
                                                  and int(r["trial"]) < trials))}
    folder.planned, folder.planned_done = total, min(len(done), total)


def _lock_holder(folder: Path) -> str:
    """Who holds the bench lock of the folder ("" when no bench is writing into it)."""
    from cramlite.bench.lock import LOCK_NAME

    path = folder / LOCK_NAME
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return ""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return ""
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return os.read(fd, 4096).decode("utf-8", "replace").strip() or "another process"
        fcntl.flock(fd, fcntl.LOCK_UN)
        return ""
    finally:
        os.close(fd)
