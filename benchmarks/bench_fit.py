"""Benchmark: the full OPM grid search on the table-setting data (xy and xyz, 100 repeats,
1,100 grid points per projection as in Table 3.4). Target: median < 60 s wall.

Run: .venv/bin/python benchmarks/bench_fit.py [--runs 5]
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
    args = parser.parse_args()
    times = []
    for run in range(args.runs):
        start = time.perf_counter()
        episodes, _ = load_episodes(DATA)
        with tqdm(total=2 * len(episodes), desc=f"fit run {run + 1}", unit="ep") as bar:
            result = fit(episodes, "opm", dims=["xy", "xyz"], metric="ape", repeats=100,
                         seed=run, progress=bar.update)
        times.append(time.perf_counter() - start)
        dims, index = result.best()
        print(f"run {run + 1}: {times[-1]:.2f} s, best {dims} {result.params(index)} "
              f"mean {result.means(dims)[index]:.3f}")
    print(f"full grid (2 x {len(result.configs)} points, 186 episodes, 100 repeats): "
          f"median {statistics.median(times):.2f} s wall (target < 60 s)")


if __name__ == "__main__":
    main()
