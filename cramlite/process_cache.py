"""Bounded caches kept for the whole process, for pure functions of the PR2's model and
the kitchen's geometry (IK along a handle, 2D maps, carry poses, arm outlines).

A world caches what it works out in `World.cache`; what does not depend on the world's
state beyond the arguments is also kept here, so that another world of the same kitchen
(the next setup a bench worker loads) reuses it. A cache that reaches its limit starts
afresh (a bench over many random setups must not grow without bound).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

Value = TypeVar("Value")


class ProcessCache(Generic[Value]):
    """A dictionary of at most `limit` entries, cleared when full."""

    def __init__(self, limit: int):
        self.limit = limit
        self._entries: dict[Hashable, Value] = {}

    def get_or_compute(self, key: Hashable, compute: Callable[[], Value]) -> Value:
        """The value for `key`, computed (and kept) if it is not known. (Threads of one
        worker may both compute it: the same answer, kept once.)"""
        try:
            return self._entries[key]
        except KeyError:
            pass
        value = compute()
        if len(self._entries) >= self.limit:
            self._entries.clear()
        self._entries[key] = value
        return value

    def __len__(self) -> int:
        return len(self._entries)

    def clear(self) -> None:
        self._entries.clear()
