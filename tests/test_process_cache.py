"""The process-wide caches: computed once per key, bounded."""

from __future__ import annotations

from cramlite.process_cache import ProcessCache


def test_a_value_is_computed_once_and_the_cache_starts_afresh_when_full() -> None:
    calls: list[int] = []
    cache: ProcessCache[int] = ProcessCache(limit=3)

    def square(n: int) -> int:
        return cache.get_or_compute(n, lambda: calls.append(n) or n * n)

    assert [square(n) for n in (1, 2, 1, 2, 3)] == [1, 4, 1, 4, 9]
    assert calls == [1, 2, 3]
    assert square(4) == 16 and len(cache) == 1  # full at 3: cleared, then 4 kept
    assert square(1) == 1 and calls == [1, 2, 3, 4, 1]
