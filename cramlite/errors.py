"""Errors a user can cause (bad input) as opposed to bugs.

`UserInputError` carries where the problem is (file, field) and what was expected,
so the command line can print it as one line and exit with code 2.
"""

from __future__ import annotations


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
