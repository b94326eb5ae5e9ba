"""Trial speed on each backend: wall_s of the first trial of a process and the median of
the following ones, for v1 and c1 (the #21 targets: kinematic v1 <= 0.25 s, c1 <= 0.6 s),
and the process's CPU time in those trials (`time.process_time`): where it is below the
wall clock, the trials waited for a core (other work on the machine); where both move
together from one hour to the next, the machine itself ran slower (instruction counts,
`bench_instructions.py`, do not move).

    python benchmarks/bench_backends.py [--backends kinematic,pybullet] [--trials 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

from cramlite.backends import runnable_backends
from cramlite.trial import TrialRunner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--backends", default=",".join(b for b in ("kinematic", "pybullet")
                                                       if b in runnable_backends()))
    parser.add_argument("--setups", default="v1,c1")
    parser.add_argument("--strategy", default="opm")
    parser.add_argument("--trials", type=int, default=5)
    args = parser.parse_args()
    for backend in args.backends.split(","):
        for setup in args.setups.split(","):
            start = time.perf_counter()
            with TrialRunner(setup, backend=backend) as runner:
                loaded = time.perf_counter() - start
                walls, cpus = [], []
                for k in range(args.trials):
                    cpu = time.process_time()
                    walls.append(runner.run(args.strategy, seed=k).wall_s)
                    cpus.append(time.process_time() - cpu)
            print(f"{backend:10s} {setup}: load {loaded:.3f} s, first trial {walls[0]:.3f} s, "
                  f"median of the next {len(walls) - 1}: {statistics.median(walls[1:]):.3f} s "
                  f"(CPU {statistics.median(cpus[1:]):.3f} s)")


if __name__ == "__main__":
    main()
