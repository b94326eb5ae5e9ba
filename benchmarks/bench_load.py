"""Benchmark: loading a setup headless: its planning scene (checked) and its PyBullet
world (kitchen, PR2, items). Target: median < 0.5 s.

Run: .venv/bin/python benchmarks/bench_load.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import statistics
import time

from cramlite.backends.pybullet.world import World
from cramlite.scene import PlanningScene
from cramlite.scene.validate import check_setup
from cramlite.world import load_setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    for name in ["v1", "v2", "v3", "v4", "v5"]:
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            setup = load_setup(name)
            check_setup(PlanningScene(setup))
            world = World.from_setup(setup)
            times.append(time.perf_counter() - start)
            world.close()
        print(f"{name}: load median {statistics.median(times) * 1000:.1f} ms "
              f"(min {min(times) * 1000:.1f}, max {max(times) * 1000:.1f}, n={args.repeats})")


if __name__ == "__main__":
    main()
