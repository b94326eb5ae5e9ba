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
import sys
import threading
import warnings
from collections.abc import Iterator


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
