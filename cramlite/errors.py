"""Errors a user can cause (bad input) as opposed to bugs.

`UserInputError` carries where the problem is (file, field) and what was expected,
so the command line can print it as one line and exit with code 2.
"""

from __future__ import annotations

#: The longest message kept in a results row or a task tree: an exception of a plugin can
#: carry megabytes of text, and a CSV reader refuses a cell over 128 KiB.
MESSAGE_LIMIT = 4000


def bounded_text(text: str, limit: int = MESSAGE_LIMIT) -> str:
    """`text`, cut to `limit` characters (saying how many were cut) if it is longer."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]} ... ({len(text) - limit} more characters)"


class UserInputError(Exception):
    """Bad input from a user: a file, a field or a value that is not what was expected."""

    def __init__(self, message: str, *, source: str | None = None, field: str | None = None):
        self.source = source
        self.field = field
        self.detail = message
        where = ": ".join(part for part in (source, field) if part)
        super().__init__(f"{where}: {message}" if where else message)


class SetupError(UserInputError):
    """A setup file that is missing, malformed or describes an impossible scene."""
