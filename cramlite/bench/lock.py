"""One bench per results folder: an exclusive lock on OUT/.bench.lock.

The lock is an OS file lock (`fcntl.flock`), so it is released when its holder exits,
however it exits: a killed bench leaves no stale lock. A process forked from the holder
(a bench's workers, the report's drawing processes) closes its copy of the lock's file
at once, so the lock goes with the holder, not with the last of them. The file names the
holder (pid, host, start time, command), which a second bench reports when it is refused.
"""

from __future__ import annotations

import os
import socket
import sys
import time
import weakref
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - not on POSIX: no locking
    fcntl = None  # type: ignore[assignment]

LOCK_NAME = ".bench.lock"


class FolderBusy(Exception):
    """Another process holds the folder's lock."""

    def __init__(self, folder: Path, holder: str):
        self.folder, self.holder = folder, holder
        super().__init__(f"{folder} is in use by another bench ({holder or 'unknown holder'})")


class FolderLock:
    """Exclusive use of a results folder; a context manager."""

    def __init__(self, folder: Path):
        self.path = Path(folder) / LOCK_NAME
        self._fd: int | None = None
        self._watches_forks = False

    def acquire(self) -> None:
        """Take the lock or raise FolderBusy naming the holder (OSError if unwritable)."""
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 4096).decode("utf-8", "replace").strip()
                os.close(fd)
                raise FolderBusy(self.path.parent, holder) from None
        os.ftruncate(fd, 0)
        command = " ".join(["cramlite", *sys.argv[1:]])[:300]
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}, since "
                     f"{time.strftime('%Y-%m-%d %H:%M:%S')}: {command}\n".encode())
        self._fd = fd
        if hasattr(os, "register_at_fork") and not self._watches_forks:
            # (once a lock: a callback cannot be unregistered, and after a release it
            # finds nothing to close)
            mine = weakref.ref(self)
            os.register_at_fork(after_in_child=lambda: _close_in_child(mine()))
            self._watches_forks = True

    def release(self) -> None:
        if self._fd is not None:
            os.ftruncate(self._fd, 0)
            os.close(self._fd)  # closing releases the flock
            self._fd = None

    def __enter__(self) -> FolderLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _close_in_child(lock: FolderLock | None) -> None:
    """In a forked process: close its copy of the lock's file (the holder keeps the lock:
    an flock ends only with an unlock or when every copy is closed, and this is neither
    the unlock nor, in the holder, a close)."""
    if lock is not None and lock._fd is not None:
        os.close(lock._fd)
        lock._fd = None
