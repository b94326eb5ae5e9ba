"""Benchmark: learned strategies on the shipped table-setting data. Targets:
- training each model (rnn, nn, cpt; 300 epochs at most, early stopping) < 60 s wall
- one learned decision for the robot (5 items, v1-like) < 5 ms

Run: .venv/bin/python benchmarks/bench_learning.py [--runs 3] [--out /tmp/bench-models]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from cramlite.learning.train import train_model
from cramlite.resources import shipped_data_path
from cramlite.strategies import Candidate, make_strategy

DATA = shipped_data_path("table-setting")
FIVE = [Candidate("spoon", (1.45, 0.35, 0.85)), Candidate("cereal", (-0.85, 1.75, 0.86)),
        Candidate("milk", (1.45, -0.15, 0.85)), Candidate("cup", (1.45, 0.85, 0.85)),
        Candidate("bowl", (1.45, -0.65, 0.85), category="mid")]


def decision_ms(model: Path, repeats: int = 200) -> float:
    strategy = make_strategy(f"learned:{model}", rng=0)
    samples = []
    for _ in range(repeats):
        strategy.reset(FIVE, (-0.5, -1.8, 0.0))
        start = time.perf_counter()
        chosen = strategy.choose(FIVE, (-0.5, -1.8, 0.0))
        samples.append(time.perf_counter() - start)
        rest = [c for c in FIVE if c is not chosen]
        start = time.perf_counter()
        strategy.choose(rest, (-0.9, 1.3, 0.0))  # a later decision: history of one item
        samples.append(time.perf_counter() - start)
    return statistics.median(samples) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--out", default=None, help="folder for the trained models")
    args = parser.parse_args()
    folder = Path(args.out or tempfile.mkdtemp(prefix="bench-models-"))
    folder.mkdir(parents=True, exist_ok=True)
    for kind in ("rnn", "nn", "cpt"):
        times, epochs = [], []
        for run in range(args.runs):
            start = time.perf_counter()
            report = train_model(DATA, kind, folder / f"{kind}.model", seed=run)
            times.append(time.perf_counter() - start)
            epochs.append(report["training"]["epochs_run"])
        ms = decision_ms(folder / f"{kind}.model")
        print(f"{kind}: training median {statistics.median(times):.1f} s wall over "
              f"{args.runs} seeds (epochs {epochs}; target < 60 s); one decision median "
              f"{ms:.3f} ms (target < 5 ms)")


if __name__ == "__main__":
    main()
