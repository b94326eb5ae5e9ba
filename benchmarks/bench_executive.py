"""Benchmark the executive. Targets (medians, headless, this 2-core machine):
- one trial of v1 (set-table, baseline and opm) < 2 s wall (world loading excluded, as
  in `wall_s`; the loading time is reported beside it)
- an IK solve (torso + arm, reachable target) < 5 ms
- one base plan (OMPL, a query whose straight line is blocked) < 50 ms

Run: .venv/bin/python benchmarks/bench_executive.py [--trials 7]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from cramlite.motion import BaseMotionPlanner, FootprintChecker, OccupancyMap, arm_ik
from cramlite.trial import TrialRunner
from cramlite.world import World, load_setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--trials", type=int, default=7)
    args = parser.parse_args()

    for strategy in ("baseline", "opm"):
        walls, totals = [], []
        for seed in range(args.trials):
            start = time.perf_counter()
            with TrialRunner("v1") as runner:
                result = runner.run(strategy, seed=seed)
            totals.append(time.perf_counter() - start)
            walls.append(result.wall_s)
            assert result.success
        print(f"v1 trial ({strategy}): wall_s median {statistics.median(walls):.3f} s, "
              f"with world loading {statistics.median(totals):.3f} s (n={args.trials}; "
              "target < 2 s)")

    ik = arm_ik("right")
    rng = np.random.default_rng(0)
    targets = [ik.forward(ik.from_q(ik.random_q(rng))) for _ in range(300)]
    times, failures = [], 0
    for target in targets:
        start = time.perf_counter()
        failures += ik.solve(target, rng) is None
        times.append(time.perf_counter() - start)
    print(f"IK solve (reachable, random start): median {statistics.median(times) * 1e3:.2f} ms, "
          f"p90 {np.percentile(times, 90) * 1e3:.2f} ms, {failures}/300 unsolved (target < 5 ms)")

    with World.from_setup(load_setup("v1")) as world:
        planner = BaseMotionPlanner(FootprintChecker(OccupancyMap(world.environment_boxes())))
        queries = {"start -> island (blocked straight line)":
                   ((-0.5, -1.8, math.pi / 2), (-0.3, 1.4, math.pi)),
                   "counter -> island": ((0.85, -0.46, 0.0), (-0.3, 1.4, math.pi)),
                   "around the island corner": ((-0.3, 0.1, 0.0), (-1.95, 1.7, math.pi / 2))}
        for name, (a, b) in queries.items():
            times = []
            for seed in range(21):
                start = time.perf_counter()
                path = planner.plan(a, b, np.random.default_rng(seed))
                times.append(time.perf_counter() - start)
                assert path is not None
            print(f"base plan, {name}: median {statistics.median(times) * 1e3:.1f} ms "
                  "(target < 50 ms)")


if __name__ == "__main__":
    main()
