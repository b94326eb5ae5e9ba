"""The planning scene's collision checks of one trial, replayed: every `is_free` and
`first_collision` call (the batches: `states_free` and OMPL's motions ask it) a c1 trial
(kinematic backend) makes, timed again on the same checks (a fixed workload, to compare
changes of the checker; medians of 5 replays).

    python benchmarks/bench_collision_calls.py [--setup c1]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from cramlite.scene import collision
from cramlite.trial import TrialRunner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--setup", default="c1")
    args = parser.parse_args()
    calls: list[tuple] = []
    check_class = collision.MotionCheck
    is_free, first_collision = check_class.is_free, check_class.first_collision

    def spy_free(self, q, margin_m=0.0):
        calls.append((is_free, self, (np.array(q, dtype=float), margin_m)))
        return is_free(self, q, margin_m)

    def spy_batch(self, states, order=None, margin_m=0.0):
        calls.append((first_collision, self, (np.array(states, dtype=float),
                                              None if order is None else list(order),
                                              margin_m)))
        return first_collision(self, states, order, margin_m)

    check_class.is_free, check_class.first_collision = spy_free, spy_batch
    with TrialRunner(args.setup, backend="kinematic") as runner:
        runner.run("opm", seed=0)
    check_class.is_free, check_class.first_collision = is_free, first_collision
    answers = [fn(check, *arguments) for fn, check, arguments in calls]
    times = []
    for _ in range(5):
        start = time.perf_counter()
        again = [fn(check, *arguments) for fn, check, arguments in calls]
        times.append(time.perf_counter() - start)
        assert again == answers
    singles = sum(fn is is_free for fn, *_ in calls)
    states = sum(len(arguments[0]) if fn is first_collision else 1
                 for fn, _, arguments in calls)
    print(f"{args.setup}: {singles} is_free and {len(calls) - singles} batch calls "
          f"({states} states): {statistics.median(times):.3f} s (median of 5)")


if __name__ == "__main__":
    main()
