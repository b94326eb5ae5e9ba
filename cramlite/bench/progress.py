"""Batch progress: a live bar on a terminal, a quiet line every 10 % otherwise.

Progress is a courtesy: if its stream fails (a closed pipe, `2>&1 | head -1`), it goes
silent and the batch goes on unchanged.
"""

from __future__ import annotations

import sys
import time
from typing import Any


class Progress:
    def __init__(self, total: int, already: int = 0, stream=None):
        self.stream = stream or sys.stderr
        self.total, self.done, self.failed = total, 0, 0
        self.already = already
        self.start = time.perf_counter()
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._bar = None
        self._next_report = 0.1
        self.silent = False
        if self.tty:
            self._quietly(lambda: setattr(self, "_bar", _bar_class()(
                total=total, desc="trials", unit="trial", file=self.stream,
                dynamic_ncols=True)))

    def say(self, message: str) -> None:
        """One line `bench: MESSAGE` (above the bar on a terminal)."""
        if self._bar is not None:
            self._quietly(lambda: self._bar.write(f"bench: {message}", file=self.stream))
        else:
            self._quietly(lambda: print(f"bench: {message}", file=self.stream, flush=True))

    def _quietly(self, write) -> None:
        if self.silent:
            return
        try:
            write()
        except (OSError, ValueError):  # closed or broken stream: stay quiet from now on
            self.silent = True

    def update(self, row: dict[str, Any]) -> None:
        self.done += 1
        self.failed += not _truthy(row.get("success"))
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed * 60 if elapsed > 0 else 0.0
        left = (self.total - self.done) / (self.done / elapsed) if self.done else 0.0
        if self._bar is not None:
            def advance() -> None:
                self._bar.set_postfix(failed=self.failed, rate=f"{rate:.0f}/min")
                self._bar.update(1)
            self._quietly(advance)
        elif self.total and (self.done / self.total >= self._next_report
                             or self.done == self.total):
            self.say(f"{self.done}/{self.total} trials, {self.failed} failed, "
                     f"{rate:.1f}/min, ~{left:.0f} s left")
            while self._next_report <= self.done / self.total:
                self._next_report += 0.1

    def close(self) -> None:
        if self._bar is not None:
            self._quietly(self._bar.close)


def _truthy(value: Any) -> bool:
    return value is True or str(value) == "True"


def _bar_class() -> type:
    """tqdm's bar without its monitor thread (which only tunes how often a stalled bar
    redraws): a bench that runs no other thread forks its workers (`cramlite.forking`)."""
    from tqdm import tqdm

    class Bar(tqdm):
        monitor_interval = 0

    return Bar
