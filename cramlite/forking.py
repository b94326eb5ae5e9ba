"""When worker processes may be forked from this one rather than started afresh.

A forked worker starts with what this process has imported (a bench's workers skip
importing cramlite: about 0.3 s of CPU each), but a fork copies only the forking thread:
a lock another thread holds stays held in the child for ever. So fork only on Linux
(macOS's system libraries are not safe to fork), when this process runs no other Python
thread, and not with JAX loaded (a learned strategy's, which runs threads of its own);
elsewhere, spawn.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
import warnings
from collections.abc import Iterator

#: How often a worker checks that the process that started it is still alive.
PARENT_CHECK_S = 1.0


def fork_is_safe() -> bool:
    """May this process fork workers now? (See the module's docstring.)"""
    return (sys.platform.startswith("linux") and threading.active_count() == 1
            and "jax" not in sys.modules)


@contextlib.contextmanager
def quiet_fork() -> Iterator[None]:
    """Python 3.12+ warns of any thread at a fork; numpy's BLAS keeps idle ones, which
    are safe to fork (they hold no lock a worker needs): that warning is silenced here."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*use of fork\\(\\) may lead to deadlocks",
                                category=DeprecationWarning)
        yield


def exit_with_parent(parent_pid: int) -> None:
    """In a worker process: exit (at once, as a killed parent cannot wait for it) within
    `PARENT_CHECK_S` of the process that started it going away, however it went (a
    SIGKILL leaves no chance to stop its workers)."""
    def watch() -> None:
        while True:
            time.sleep(PARENT_CHECK_S)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="cramlite-parent-watch", daemon=True).start()
