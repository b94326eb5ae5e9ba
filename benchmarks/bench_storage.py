"""Benchmark closed storage. Target (median, headless, this 2-core machine):
- one trial of c1 (set-table; spoon and bowl in the drawers, cup in the cupboard), with
  every container opened and closed along checked handle paths: wall_s <= 1.2 s (world
  loading excluded, as in `wall_s`)
It also prints where a trial's wall time goes (median share per part over the trials),
with the storage parts (accessing locations, handle IK) on their own lines.

Run: .venv/bin/python benchmarks/bench_storage.py [--trials 7] [--setup c1]
"""

from __future__ import annotations

import argparse
import collections
import statistics
import time

from bench_executive import PARTS, timed_parts

from cramlite.designators import storage
from cramlite.trial import TrialRunner

STORAGE_PARTS = [
    ("accessing locations (handle IK, checks)", storage.AccessingLocation, "reach_from"),
    ("accessing locations (handle IK, checks)", storage, "_footprint_free"),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--trials", type=int, default=7)
    parser.add_argument("--setup", default="c1")
    args = parser.parse_args()

    PARTS[:0] = STORAGE_PARTS  # outermost first: nested IK and checks count here
    shares: dict[str, list[float]] = collections.defaultdict(list)
    for strategy in ("baseline", "opm"):
        walls, totals, open_close = [], [], []
        for seed in range(args.trials):
            start = time.perf_counter()
            with TrialRunner(args.setup) as runner, timed_parts() as spent:
                result = runner.run(strategy, seed=seed)
            totals.append(time.perf_counter() - start)
            walls.append(result.wall_s)
            open_close.append(result.open_close_s)
            assert result.success, result.failures
            for label in dict.fromkeys(label for label, _, _ in PARTS):
                shares[label].append(spent[label] / result.wall_s)
            shares["other (designators, strategy, Python)"].append(
                1 - sum(spent.values()) / result.wall_s)
        print(f"{args.setup} trial ({strategy}): wall_s median {statistics.median(walls):.3f} s "
              f"(min {min(walls):.3f}, max {max(walls):.3f}), with world loading "
              f"{statistics.median(totals):.3f} s (n={args.trials}; target <= 1.2 s); robot "
              f"time opening and closing: median {statistics.median(open_close):.1f} s")
    print("where the wall time goes (median share over the trials above; the timers add "
          "a little):")
    for label, values in shares.items():
        print(f"  {label:<42} {statistics.median(values) * 100:5.1f} %")


if __name__ == "__main__":
    main()
