"""Silence the C-level prints of PyBullet.

PyBullet writes warnings and URDF diagnostics straight to file descriptors 1 and 2
from C code, which breaks machine-readable output (`--json`). Only a descriptor-level
redirect silences them (see shared/PITFALLS.md); libc's buffer is flushed inside the
redirect so nothing buffered escapes later.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from collections.abc import Iterator


@contextlib.contextmanager
def c_output_silenced(stderr: bool = False) -> Iterator[None]:
    """Redirect file descriptor 1 (and 2 if asked) to /dev/null for the block."""
    streams = [sys.stdout, sys.stderr]
    for stream in streams:
        with contextlib.suppress(Exception):
            stream.flush()
    fds = [1, 2] if stderr else [1]  # C code writes to the descriptors, whatever sys.* are
    saved = [os.dup(fd) for fd in fds]
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in fds:
            os.dup2(devnull, fd)
        yield
    finally:
        for stream in streams:
            with contextlib.suppress(Exception):
                stream.flush()
        _flush_c_stdio()
        for fd, copy in zip(fds, saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


def c_stdout_silenced() -> contextlib.AbstractContextManager[None]:
    return c_output_silenced(stderr=False)


def _flush_c_stdio() -> None:
    with contextlib.suppress(Exception):
        ctypes.CDLL(None).fflush(None)
