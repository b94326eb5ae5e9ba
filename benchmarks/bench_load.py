"""Benchmark: loading a setup (world + PR2 + items) headless. Target: median < 0.5 s.

Run: .venv/bin/python benchmarks/bench_load.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import statistics
import time

from cramlite.world import World, load_setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    for name in ["v1", "v2", "v3", "v4", "v5"]:
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            setup = load_setup(name)
            world = World.from_setup(setup)
            times.append(time.perf_counter() - start)
            world.close()
        print(f"{name}: load median {statistics.median(times) * 1000:.1f} ms "
              f"(min {min(times) * 1000:.1f}, max {max(times) * 1000:.1f}, n={args.repeats})")


if __name__ == "__main__":
    main()
