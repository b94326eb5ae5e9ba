"""Benchmark: ordering decisions. Targets (CPU time, medians):
- `opm` decision over 5 items < 20 us
- `opm` decision over 100,000 candidates < 10 ms (vectorised)
- `optimal` on 12 items < 2 s

Run: .venv/bin/python benchmarks/bench_strategies.py
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from cramlite.strategies import Candidate, make_strategy


def cpu_median(fn, repeats: int, inner: int = 1) -> float:
    samples = []
    for _ in range(repeats):
        start = time.process_time()
        for _ in range(inner):
            fn()
        samples.append((time.process_time() - start) / inner)
    return statistics.median(samples)


def main() -> None:
    rng = np.random.default_rng(0)
    opm = make_strategy("opm", rng=0)
    five = [Candidate(n, tuple(rng.uniform(-2, 2, 3)), category=cat)
            for n, cat in zip(["spoon", "cereal", "milk", "cup", "bowl"],
                              ["none", "none", "none", "none", "mid"], strict=True)]
    agent = (-0.5, -1.8, 0.0)
    t5 = cpu_median(lambda: opm.choose(five, agent), repeats=15, inner=20000)
    print(f"opm decision, 5 items: median {t5 * 1e6:.2f} us CPU (target < 20 us)")

    n = 100_000
    positions = rng.uniform(-5, 5, (n, 3))
    k = rng.choice([0.2, 0.3, 1.0, 1.2], n)
    c = rng.choice([1.0, 1.7], n)
    t100k = cpu_median(lambda: opm.choose_index(agent, positions, k, c), repeats=31)
    print(f"opm decision, 100,000 candidates: median {t100k * 1e3:.2f} ms CPU (target < 10 ms)")

    twelve = [Candidate(f"i{i}", tuple(rng.uniform(-2, 2, 3)), then_at=(-0.3, 1.3, 0.0))
              for i in range(12)]
    optimal = make_strategy("optimal", rng=0)
    t12 = cpu_median(lambda: optimal.plan(twelve, agent), repeats=5)
    print(f"optimal plan, 12 items: median {t12:.3f} s CPU (target < 2 s)")


if __name__ == "__main__":
    main()
