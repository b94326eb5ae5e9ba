"""Loading recorded human sequences (the published OPM data format) into episodes.

Columns: ID, sequence (comma-separated item names; a name may repeat), coordinates
(`name: (x,y,z);...`, a repeated name listed once per instance), start_coordinates
(`[x,y,z],...`: the subject's position before each action), strong_k, mid_k, food_k,
containment (item-name lists, `0` or empty = none), error (the published random
baseline), and optionally activity. The same format covers table setting, cooking and
clearing up.

Repeated names are distinct items at their own positions: the j-th time a name occurs
in the sequence it is the j-th listed instance of that name. Where a name is taken more
often than it is listed (grid-annotated sets list three glasses in one cupboard once),
the extra instances stand at the name's last listed position. A name taken but never
listed is a bad row.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from cramlite.errors import UserInputError
from cramlite.file_limits import checked_file
from cramlite.strategies.candidates import Candidate, Position

REQUIRED_COLUMNS = ("ID", "sequence", "coordinates", "start_coordinates")
CATEGORY_COLUMNS = {"strong_k": "strong", "mid_k": "mid", "food_k": "food"}
_COORD = re.compile(r"^\s*([^:;]+?)\s*:\s*\(\s*([^()]+?)\s*\)\s*$")
_START = re.compile(r"\[([^\[\]]*)\]")
_ACTIVITY_BY_ID = [
    (re.compile(r"^k\d+$"), "cleaning up"),
    (re.compile(r"^s\d+-d\d+$"), "cooking"),
    (re.compile(r"^(T\d+|[PE]\d+_\d+|a\d+|h\d+|v\d+)$"), "table setting"),
]


class DataError(UserInputError):
    """A row of a sequence file that cannot be used (names the row ID and column)."""


@dataclass(frozen=True)
class Episode:
    """One recorded sequence: what was fetched, from where, and where the subject stood."""

    id: str
    activity: str
    sequence: tuple[str, ...]
    items: tuple[Candidate, ...]  # every listed instance, in listing order
    taken: tuple[int, ...]  # for each step, the index into `items` of what was fetched
    start_positions: tuple[Position, ...]  # one per step (extra ones are dropped)
    published_baseline: float | None = None
    extra: dict[str, str] = field(default_factory=dict, compare=False)
    #: The raw k and containment cells (the reference protocol reads them as text).
    cells: dict[str, str] = field(default_factory=dict, compare=False)

    def __len__(self) -> int:
        return len(self.sequence)

    def sequence_items(self) -> tuple[Candidate, ...]:
        """The items of the action list (Algorithm 1's candidates), one per step."""
        return tuple(self.items[i] for i in self.taken)


@dataclass(frozen=True)
class BadRow:
    id: str
    field: str
    message: str

    def __str__(self) -> str:
        return f"row {self.id}: {self.field}: {self.message}"


def _names(cell: str | None) -> set[str]:
    if cell is None:
        return set()
    return {n.strip() for n in cell.split(",") if n.strip() and n.strip() != "0"}


def _floats(text: str, row_id: str, column: str) -> Position:
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise DataError(f"expected numbers x,y,z, got ({text})", field=column,
                        source=f"row {row_id}") from None
    if not all(math.isfinite(v) for v in values):
        raise DataError(f"expected finite numbers x,y,z, got ({text})", field=column,
                        source=f"row {row_id}")
    if len(values) == 2:
        values.append(0.0)
    if len(values) != 3:
        raise DataError(f"expected 3 coordinates (x,y,z), got {len(values)}", field=column,
                        source=f"row {row_id}")
    return (values[0], values[1], values[2])


def activity_of(row: dict[str, str]) -> str:
    if row.get("activity"):
        return row["activity"].strip()
    for pattern, activity in _ACTIVITY_BY_ID:
        if pattern.match(row["ID"].strip()):
            return activity
    return "unknown"


def parse_row(row: dict[str, str]) -> Episode:
    """One CSV row as an Episode; raises DataError naming the ID and the field."""
    row_id = (row.get("ID") or "").strip() or "?"

    def fail(column: str, message: str) -> DataError:
        return DataError(message, source=f"row {row_id}", field=column)

    if row_id == "?":
        raise fail("ID", "expected the episode's ID, got nothing")
    sequence = tuple(n.strip() for n in (row.get("sequence") or "").split(",") if n.strip())
    if not sequence:
        raise fail("sequence", "expected comma-separated item names, got nothing")
    categories = {name: cat for column, cat in CATEGORY_COLUMNS.items()
                  for name in _names(row.get(column))}
    contained = _names(row.get("containment"))
    items: list[Candidate] = []
    for part in (row.get("coordinates") or "").split(";"):
        if not part.strip():
            continue
        match = _COORD.match(part)
        if not match:
            raise fail("coordinates", f"expected 'name: (x,y,z)', got {part.strip()!r}")
        name = match.group(1)
        items.append(Candidate(name=name, position=_floats(match.group(2), row_id,
                                                            "coordinates"),
                               category=categories.get(name, "none"),
                               contained=name in contained))
    listed = Counter(c.name for c in items)
    for name, count in Counter(sequence).items():
        if listed[name] == 0:
            raise fail("coordinates", f"the sequence takes {name!r} but it has no "
                                      "coordinates; expected 'name: (x,y,z)' for it")
        last = [c for c in items if c.name == name][-1]
        items.extend([last] * (count - listed[name]))
    starts = [_floats(m, row_id, "start_coordinates")
              for m in _START.findall(row.get("start_coordinates") or "")]
    if len(starts) < len(sequence):
        raise fail("start_coordinates", f"expected at least {len(sequence)} start positions "
                                        f"(one per step), got {len(starts)}")
    taken, seen = [], Counter()
    instances: dict[str, list[int]] = {}
    for index, item in enumerate(items):
        instances.setdefault(item.name, []).append(index)
    for name in sequence:
        taken.append(instances[name][seen[name]])
        seen[name] += 1
    baseline = None
    try:
        baseline = float(row["error"]) if row.get("error") not in (None, "") else None
    except ValueError:
        raise fail("error", f"expected a number, got {row['error']!r}") from None
    if baseline is not None and not math.isfinite(baseline):
        raise fail("error", f"expected a finite number, got {row['error']!r}")
    known = set(REQUIRED_COLUMNS) | set(CATEGORY_COLUMNS) | {"containment", "error", "activity"}
    return Episode(id=row_id, activity=activity_of(row), sequence=sequence, items=tuple(items),
                   taken=tuple(taken), start_positions=tuple(starts[:len(sequence)]),
                   published_baseline=baseline,
                   extra={k: v for k, v in row.items() if k not in known and k is not None},
                   cells={k: row.get(k) or "" for k in (*CATEGORY_COLUMNS, "containment")})


#: The longest field accepted (csv's own limit, said in the error message).
MAX_FIELD_BYTES = 128 * 1024


def iter_rows(path: str | Path) -> Iterator[dict[str, str]]:
    """The rows of a CSV file; a file that is not UTF-8 text, not a regular file, lacks a
    required column or holds a field over 128 KiB raises DataError naming it."""
    path = Path(path)
    if path.is_dir():
        raise DataError("expected a CSV file, got a folder", source=str(path))
    checked_file(path, "data", DataError)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        from cramlite.resources import SHIPPED_DATA

        raise DataError("no such file; expected a CSV file of recorded sequences or a shipped "
                        f"set: {', '.join(SHIPPED_DATA)}", source=str(path)) from None
    except OSError as exc:
        raise DataError(f"cannot read file ({exc.strerror})", source=str(path)) from None
    try:
        text = raw.decode("utf-8-sig")  # (a byte-order mark, as spreadsheets write, is fine)
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise DataError(f"expected UTF-8 text, got byte 0x{raw[exc.start]:02x}",
                        source=f"{path}: line {line}") from None
    with io.StringIO(text, newline="") as handle:
        reader = csv.DictReader(handle)
        try:
            missing = [c for c in REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
            if missing:
                raise DataError(f"missing column(s) {', '.join(missing)}; expected at least "
                                f"{', '.join(REQUIRED_COLUMNS)}", source=str(path),
                                field="header")
            yield from reader
        except csv.Error as exc:
            if "field larger than field limit" in str(exc):
                raise DataError(f"a field is longer than {MAX_FIELD_BYTES // 1024} KiB; "
                                "expected shorter cells", source=f"{path}: line "
                                f"{reader.line_num + 1}") from None
            raise DataError(f"not a readable CSV file ({exc})",
                            source=f"{path}: line {reader.line_num}") from None


def load_episodes(path: str | Path, on_bad_row: str = "fail",
                  ) -> tuple[list[Episode], list[BadRow]]:
    """All episodes of a file. `on_bad_row`: "fail" raises at the first bad row,
    "skip" leaves it out and reports it in the returned list."""
    if on_bad_row not in ("fail", "skip"):
        raise ValueError("on_bad_row must be 'fail' or 'skip'")
    episodes, bad = [], []
    seen: set[str] = set()
    for number, row in enumerate(iter_rows(path), start=1):
        try:
            episode = parse_row(row)
            if episode.id in seen:  # (results are keyed and paired by ID)
                raise DataError("duplicate; expected every episode to have its own ID",
                                source=f"row {episode.id}", field="ID")
            seen.add(episode.id)
            episodes.append(episode)
        except DataError as exc:
            if exc.source == "row ?":  # (no ID to name it by)
                exc.source = f"data row {number}"
            if on_bad_row == "fail":
                raise DataError(exc.detail, source=f"{path}: {exc.source}",
                                field=exc.field) from None
            bad.append(BadRow((row.get("ID") or "").strip() or f"? (data row {number})",
                              exc.field or "", exc.detail))
    if not episodes and not bad:
        raise DataError("no rows", source=str(path))
    return episodes, bad
