"""Benchmark batch runs. Targets on this 2-core machine:
- the default run (v1-v5 x opm/baseline x 10 = 100 trials) <= 1 minute with 2 workers
- `--all-orders` on v1-v5 (600 fixed-order trials, plus the 100 default ones) < 15 minutes
Reports trials per minute for 1 and 2 workers (median of --runs runs, fresh folders).

Run: .venv/bin/python benchmarks/bench_batch.py [--runs 3] [--all-orders]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def bench(workers: int, *extra: str) -> tuple[float, int]:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = subprocess.run([sys.executable, "-m", "cramlite", "bench", "--out", out,
                                 "--workers", str(workers), "--no-plots", *extra],
                                cwd=ROOT, capture_output=True, text=True)
        elapsed = time.perf_counter() - start
        if result.returncode != 0:
            print(result.stderr[-2000:])
        rows = len((Path(out) / "trials.csv").read_text().splitlines()) - 1
    return elapsed, rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--all-orders", action="store_true", help="also time --all-orders")
    args = parser.parse_args()
    for workers in (1, 2):
        times = []
        for _ in range(args.runs):
            elapsed, rows = bench(workers)
            times.append(elapsed)
        median = statistics.median(times)
        print(f"default run ({rows} trials), {workers} worker(s): median {median:.1f} s, "
              f"{rows / median * 60:.0f} trials/min (runs: "
              f"{', '.join(f'{t:.1f}' for t in times)}; target <= 60 s with 2 workers)")
    if args.all_orders:
        elapsed, rows = bench(2, "--all-orders")
        print(f"--all-orders ({rows} trials), 2 workers: {elapsed / 60:.1f} min, "
              f"{rows / elapsed * 60:.0f} trials/min (target < 15 min)")


if __name__ == "__main__":
    main()
