"""JSON from files and cells a user (or an attacker) wrote: every way such text can fail
to parse is one `JSONInputError` (a ValueError) with a short reason, never a traceback.

`json.loads` raises three kinds of error on hostile text: `JSONDecodeError` for invalid
JSON, `RecursionError` for nesting thousands deep (`[[[[...]]]]`), and a plain
`ValueError` for an integer of more than 4,300 digits; callers catch one.
"""

from __future__ import annotations

import json
from typing import Any


class JSONInputError(ValueError):
    """Text that is not usable JSON; the message says why in a few words."""


def parse_json(text: str | bytes) -> Any:
    """The value of JSON `text`, or a JSONInputError saying why there is none."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise JSONInputError(f"not valid JSON ({exc.msg} at line {exc.lineno} column "
                             f"{exc.colno})") from None
    except RecursionError:
        raise JSONInputError("not usable JSON (nested too deeply)") from None
    except ValueError as exc:  # an integer of thousands of digits
        raise JSONInputError(f"not usable JSON ({exc})") from None


__all__ = ["JSONInputError", "parse_json"]
