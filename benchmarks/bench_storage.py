"""Benchmark closed storage. Target (median, headless, this 2-core machine):
- one trial of c1 (set-table; spoon and bowl in the drawers, cup in the cupboard), with
  every container opened and closed along checked handle paths: wall_s <= 1.2 s (world
  loading excluded, as in `wall_s`)
Each trial is run three ways: as the first trial of a process (`cramlite run --json`, a
new process each); in a new world of a process that has run one before (a bench worker
loading its next setup: IK along the handles and the 2D maps are kept for the process);
and in a world that ran one trial before (a bench worker's next trial: carry poses too are
worked out once per world). It also prints where a trial's wall time goes (median share
per part), with the storage parts (accessing locations, handle IK) on their own lines.

Run: .venv/bin/python benchmarks/bench_storage.py [--trials 7] [--setup c1]
"""

from __future__ import annotations

import argparse
import collections
import json
import statistics
import subprocess
import sys

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
        # a fresh world per trial (`cramlite run`), and one world for all of them (a bench
        # worker keeps its world: what was worked out once per world is reused)
        first, fresh, reused, open_close = [], [], [], []
        for seed in range(args.trials):
            done = subprocess.run([sys.executable, "-m", "cramlite", "run", args.setup,
                                   "--strategy", strategy, "--seed", str(seed), "--json"],
                                  capture_output=True, text=True, check=True)
            first.append(json.loads(done.stdout)["wall_s"])
        for seed in range(args.trials):
            with TrialRunner(args.setup) as runner:
                result = runner.run(strategy, seed=seed)
            assert result.success, result.failures
            fresh.append(result.wall_s)
        with TrialRunner(args.setup) as runner:
            runner.run(strategy, seed=args.trials)
            for seed in range(args.trials):
                with timed_parts() as spent:
                    result = runner.run(strategy, seed=seed)
                assert result.success, result.failures
                reused.append(result.wall_s)
                open_close.append(result.open_close_s)
                for label in dict.fromkeys(label for label, _, _ in PARTS):
                    shares[label].append(spent[label] / result.wall_s)
                shares["other (designators, strategy, Python)"].append(
                    1 - sum(spent.values()) / result.wall_s)
        print(f"{args.setup} trial ({strategy}), wall_s median (n={args.trials}; target <= 1.2 s): "
              f"first of a process {statistics.median(first):.3f} s (min {min(first):.3f}, "
              f"max {max(first):.3f}); "
              f"new world {statistics.median(fresh):.3f} s (min {min(fresh):.3f}, max "
              f"{max(fresh):.3f}); world reused as in a bench {statistics.median(reused):.3f} s "
              f"(min {min(reused):.3f}, max {max(reused):.3f}); robot time opening and "
              f"closing: median {statistics.median(open_close):.1f} s")
    print("where the wall time of the reused-world trials goes (median share; the timers add "
          "a little):")
    for label, values in shares.items():
        print(f"  {label:<42} {statistics.median(values) * 100:5.1f} %")


if __name__ == "__main__":
    main()
