"""What a row of trials.csv must hold to be read back (by a resumed bench and by the
report): a row a crash cut short is skipped elsewhere; a complete row with a value no
bench writes (a trial of `²`, a success of `maybe`, a NUL byte) is refused, naming its
column, so a tampered or damaged file is one clear line instead of a wrong report."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

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


__all__ = ["row_problem"]
