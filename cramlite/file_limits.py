"""Files cramlite reads are regular files of a bounded size (a FIFO, a device such as
/dev/zero, or a symlink to one would block or exhaust memory): one check for all of them,
with a limit per kind that `CRAMLITE_MAX_FILE_MB` raises (or lowers) for every kind."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from cramlite.errors import UserInputError

#: Megabytes per kind of file (the shipped data is 0.2 MB, a c1 trace 2 MB, a model 2 MB).
LIMITS_MB = {"data": 256, "trace": 1024, "results": 1024, "model": 256, "request": 256,
             "model entry": 512}
ENV = "CRAMLITE_MAX_FILE_MB"


def limit_bytes(kind: str) -> int:
    """The limit for `kind`, or the one `CRAMLITE_MAX_FILE_MB` sets."""
    text = os.environ.get(ENV, "").strip()
    if text:
        try:
            megabytes = float(text)
        except ValueError:
            raise UserInputError(f"expected a number of megabytes, got {text!r}",
                                 field=ENV) from None
        if not megabytes > 0:
            raise UserInputError(f"expected a number of megabytes > 0, got {text!r}",
                                 field=ENV)
        return int(megabytes * 1024 * 1024)
    return LIMITS_MB[kind] * 1024 * 1024


def _what(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def checked_file(path: str | Path, kind: str, error: type[UserInputError] = UserInputError,
                 ) -> Path:
    """`path` if it is a regular file within the limit for `kind`; else `error` naming it.
    A missing or unreadable file is left to the caller's own message."""
    path = Path(path)
    try:
        info = path.stat()
    except OSError:
        return path
    if not stat.S_ISREG(info.st_mode):
        raise error(f"is {_what(info.st_mode)}; expected a regular {kind} file",
                    source=str(path))
    check_size(info.st_size, kind, str(path), error)
    return path


def check_size(size: int, kind: str, source: str,
               error: type[UserInputError] = UserInputError) -> None:
    limit = limit_bytes(kind)
    if size > limit:
        raise error(f"{size / 2**20:.1f} MB is over the {round(limit / 2**20, 3):g} MB limit for a "
                    f"{kind} file (set {ENV} to raise it)", source=source)
