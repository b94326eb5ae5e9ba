"""Benchmark: full grid fits on the table-setting data (xy and xyz, 100 repeats, 1,100
grid points per projection as in Table 3.4) for `opm`, `opm-2step` and `optimal`.
Target: median < 60 s wall per fit on this 2-core machine.

Run: .venv/bin/python benchmarks/bench_fit.py [--runs 5] [--strategies opm,opm-2step,optimal]
"""

from __future__ import annotations

import argparse
import statistics
import time

from tqdm import tqdm

from cramlite.evaluation.data import load_episodes
from cramlite.evaluation.fit import fit
from cramlite.resources import shipped_data_path

DATA = shipped_data_path("table-setting")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--strategies", default="opm,opm-2step,optimal")
    parser.add_argument("--protocol", default="heldout")
    args = parser.parse_args()
    for strategy in args.strategies.split(","):
        times = []
        for run in range(args.runs):
            start = time.perf_counter()
            episodes, _ = load_episodes(DATA)
            with tqdm(total=2 * len(episodes), desc=f"fit {strategy} run {run + 1}",
                      unit="ep", leave=False) as bar:
                result = fit(episodes, strategy, dims=["xy", "xyz"], metric="ape",
                             repeats=100, seed=run, progress=bar.update,
                             protocol=args.protocol)
            times.append(time.perf_counter() - start)
            dims, index = result.best()
            print(f"{strategy} run {run + 1}: {times[-1]:.2f} s, best {dims} "
                  f"{result.params(index)} mean {result.means(dims)[index]:.3f}")
        print(f"{strategy}: full grid (2 x {len(result.configs)} points, 186 episodes, "
              f"100 repeats): median {statistics.median(times):.2f} s wall (target < 60 s)")


if __name__ == "__main__":
    main()
