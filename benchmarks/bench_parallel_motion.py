"""What parallel motion saves: the robot time of every setup x strategy with the torso
rising and the arms parking while the base drives (the default) and with every motion one
after the other (`ExecutionOptions(parallel_motion=False)`), and the computing it costs.

    python benchmarks/bench_parallel_motion.py [--setups v1,...] [--backend kinematic]
"""

from __future__ import annotations

import argparse

from cramlite.designators.context import ExecutionOptions
from cramlite.trial import TrialRunner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--setups", default="v1,v2,v3,v4,v5,c1,c2,c3")
    parser.add_argument("--strategies", default="opm,baseline")
    parser.add_argument("--backend", default="kinematic")
    args = parser.parse_args()
    for setup in args.setups.split(","):
        for strategy in args.strategies.split(","):
            runs = {}
            for together in (True, False):
                with TrialRunner(setup, backend=args.backend,
                                 options=ExecutionOptions(parallel_motion=together)) as runner:
                    runner.run(strategy, seed=0)  # (warm: the first trial of a process)
                    runs[together] = runner.run(strategy, seed=0)
            on, off = runs[True], runs[False]
            saved = off.robot_time_s - on.robot_time_s
            print(f"{setup} {strategy:8s} robot time {off.robot_time_s:7.2f} s one after the "
                  f"other, {on.robot_time_s:7.2f} s with parallel motion: {saved:5.2f} s "
                  f"({saved / off.robot_time_s:.1%}) saved; {on.parallel_s:5.2f} s of motions "
                  f"at once; orders {'same' if on.order == off.order else 'DIFFER'}, success "
                  f"{off.success}/{on.success}; computing {off.wall_s:.2f} / {on.wall_s:.2f} s")


if __name__ == "__main__":
    main()
