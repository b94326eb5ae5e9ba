"""The planning scene's collision checks of one trial, replayed: every `is_free` and
`states_free` call a c1 trial (kinematic backend) makes, timed again on the same checks
(a fixed workload, to compare changes of the checker; medians of 5 replays).

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
    is_free, states_free = collision.MotionCheck.is_free, collision.MotionCheck.states_free

    def spy_free(self, q, margin_m=0.0):
        calls.append((is_free, self, np.array(q, dtype=float), margin_m))
        return is_free(self, q, margin_m)

    def spy_states(self, states, order=None):
        calls.append((states_free, self, np.array(states, dtype=float), order))
        return states_free(self, states, order)

    collision.MotionCheck.is_free, collision.MotionCheck.states_free = spy_free, spy_states
    with TrialRunner(args.setup, backend="kinematic") as runner:
        runner.run("opm", seed=0)
    collision.MotionCheck.is_free, collision.MotionCheck.states_free = is_free, states_free
    answers = [fn(check, a, b) for fn, check, a, b in calls]
    times = []
    for _ in range(5):
        start = time.perf_counter()
        again = [fn(check, a, b) for fn, check, a, b in calls]
        times.append(time.perf_counter() - start)
        assert again == answers
    singles = sum(fn is is_free for fn, *_ in calls)
    print(f"{args.setup}: {singles} is_free and {len(calls) - singles} states_free calls, "
          f"{sum(answers)} free: {statistics.median(times):.3f} s (median of 5)")


if __name__ == "__main__":
    main()
