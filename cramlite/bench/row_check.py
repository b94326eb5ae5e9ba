"""What a row of trials.csv must hold to be read back (by a resumed bench and by the
report): a row a crash cut short is skipped elsewhere; a complete row with a value no
bench writes (a trial of `²`, a success of `maybe`, a NUL byte) is refused, naming its
column, so a tampered or damaged file is one clear line instead of a wrong report."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

from cramlite.plan_names import PLAN_NAMES

#: Columns holding a whole number (an index or a seed).
WHOLE_COLUMNS = {"trial": 9, "seed": 20, "batch_seed": 20}
#: Columns holding a measurement: empty (a failed trial) or a finite number >= 0.
MEASURE_COLUMNS = ("base_path_m", "straight_line_m", "wall_s", "drive_s", "arm_s",
                   "open_close_s", "robot_time_s", "task_time_s")
SUCCESS_VALUES = ("True", "False")
#: Control characters no cell holds (the error text may have line breaks and tabs).
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def row_problem(row: Mapping[str, str]) -> tuple[str, str] | None:
    """(column, what is wrong) for the first unusable value of a complete row, else
    None. Only the columns the row has are checked (older formats have fewer)."""
    for column, value in row.items():
        if isinstance(value, str) and _CONTROL.search(value):
            return column, "holds a control character (a NUL byte?); expected text"
    for column, digits in WHOLE_COLUMNS.items():
        value = row.get(column)
        if value is not None and not re.fullmatch(rf"[0-9]{{1,{digits}}}", value):
            return column, f"expected a whole number, got {value[:40]!r}"
    carry = row.get("carry")
    if carry is not None and carry not in ("1", "2"):
        return "carry", f"expected 1 or 2, got {carry[:40]!r}"
    success = row.get("success")
    if success is not None and success not in SUCCESS_VALUES:
        return "success", f"expected True or False, got {success[:40]!r}"
    for column in MEASURE_COLUMNS:
        value = row.get(column)
        if not value:
            continue
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not (math.isfinite(number) and number >= 0):
            return column, f"expected a number >= 0 (or nothing), got {value[:40]!r}"
    return None


#: Columns holding JSON, and what each must be.
JSON_COLUMNS = {"failures": list, "items": dict, "actions": list, "driven_path": list}


class CellProblem(ValueError):
    """A cell of a row that no bench writes: its column and what is wrong."""

    def __init__(self, column: str, message: str):
        super().__init__(f"{column}: {message}")
        self.column = column


def parsed_json_cells(row: Mapping[str, Any]) -> dict[str, Any]:
    """The JSON columns of a row (those it has), parsed and checked as the report reads
    them: CellProblem naming the first that is not what a bench writes (the bench checks
    a folder with it before resuming, so a file the report would refuse is refused before
    any trial runs, not after all of them)."""
    from cramlite.safe_json import JSONInputError, parse_json

    out: dict[str, Any] = {}
    for column, kind in JSON_COLUMNS.items():
        if column not in row:
            continue
        cell = row.get(column) or ("[]" if kind is list else "{}")
        if isinstance(cell, str):
            try:
                value = parse_json(cell)
            except JSONInputError:
                value = None
        else:
            value = cell
        if not isinstance(value, kind):
            raise CellProblem(column, f"expected a JSON {kind.__name__}, got {str(cell)[:40]!r}")
        out[column] = value
    if not all(isinstance(p, list) and len(p) >= 2 and all(_finite(v) for v in p)
               for p in out.get("driven_path", [])):
        raise CellProblem("driven_path", "expected a list of [x, y, ...] points (finite "
                                         f"numbers), got {str(row.get('driven_path'))[:40]!r}")
    problem = _task_tree_problem(out.get("actions", []))
    if problem:
        raise CellProblem("actions", f"{problem}; expected the task tree a bench writes "
                                     "(nodes with a name, start_s, end_s, status, children)")
    return out


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        math.isfinite(value)


def _task_tree_problem(nodes: Any, depth: int = 0) -> str | None:
    if not isinstance(nodes, list):
        return f"children {str(nodes)[:30]!r} is not a list"
    for node in nodes:
        if not isinstance(node, dict):
            return f"a node {str(node)[:30]!r} is not an object"
        if not isinstance(node.get("name"), str) or not isinstance(node.get("status"), str):
            return f"a node without a name or status ({str(node)[:40]!r})"
        if not _finite(node.get("start_s")) or not (node.get("end_s") is None
                                                   or _finite(node.get("end_s"))):
            return f"node {node['name'][:30]!r}: start_s/end_s not numbers"
        problem = _task_tree_problem(node.get("children", []), depth + 1)
        if problem:
            return problem
    return None


def legs_not_reported(row: dict[str, Any]) -> dict[str, Any]:
    """The row with a user's plan's straight-line legs of exactly 0 m read as not reported
    (empty): before 2026-12-04 a plan that never called `PlanReport.add_leg` was written as
    0, which summaries and paired tests took for a distance; now it is written empty. (A
    plan that fetched anything has legs longer than 0; the built-in plans always report
    theirs.)"""
    # (read after `row_problem`: the cell is empty or a finite number)
    value = row.get("straight_line_m")
    if row.get("plan", "set-table") not in PLAN_NAMES and value and float(value) == 0.0:
        row["straight_line_m"] = ""
    return row


__all__ = ["CellProblem", "JSON_COLUMNS", "legs_not_reported", "parsed_json_cells",
           "row_problem"]
