"""Benchmark the executive. Targets (medians, headless, this 2-core machine):
- one trial of v1 (set-table, baseline and opm) with checked, timed trajectories:
  wall_s <= 0.6 s (world loading excluded, as in `wall_s`; loading is reported beside it)
- an IK solve (torso + arm, reachable target) < 5 ms
- one base plan (OMPL, a query whose straight line is blocked) < 50 ms
Each trial runs in a new world of this process (2D maps are kept for the process, so a
new world of the same kitchen reuses them) and as the first trial of a process
(`cramlite run --json`). It also prints where a trial's wall time goes (median share per
part over the in-process trials).

Run: .venv/bin/python benchmarks/bench_executive.py [--trials 7]
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import functools
import json
import math
import statistics
import subprocess
import sys
import time

import numpy as np

from cramlite.backends.pybullet import modules as process_modules
from cramlite.motion import (
    BaseMotionPlanner,
    FootprintChecker,
    OccupancyMap,
    arm_ik,
    arm_planner,
    ik,
    trajectory,
)
from cramlite.scene import PlanningScene, collision
from cramlite.trial import TrialRunner
from cramlite.world import load_setup

#: (label, owner, attribute): inclusive time of these calls, outermost call only.
PARTS = [
    ("IK (Pinocchio)", ik.ArmIK, "solve"),
    ("arm planning (OMPL detours)", arm_planner.ArmMotionPlanner, "_ompl"),
    ("collision checks outside OMPL", collision.MotionCheck, "is_free"),
    ("collision checks outside OMPL", collision.MotionCheck, "states_free"),
    ("scene observing the process modules", PlanningScene, "observe"),
    ("base planning (OMPL, 2D map)", BaseMotionPlanner, "plan"),
    ("trajectory timing (Ruckig)", trajectory, "time_joint_path"),
    ("executing trajectories", process_modules.SimulatedProcessModules,
     "execute_joint_trajectory"),
    ("executing trajectories", process_modules.SimulatedProcessModules,
     "execute_base_trajectory"),
    ("physics settling", process_modules.SimulatedProcessModules, "settle"),
]


@contextlib.contextmanager
def timed_parts():
    """Accumulate the inclusive time of PARTS (nested calls counted once, in the outer)."""
    spent: dict[str, float] = collections.defaultdict(float)
    depth = [0]
    originals = []
    for label, owner, name in PARTS:
        original = getattr(owner, name)
        originals.append((owner, name, original))

        def wrap(fn, label=label):
            @functools.wraps(fn)
            def timed(*args, **kwargs):
                depth[0] += 1
                start = time.perf_counter()
                try:
                    return fn(*args, **kwargs)
                finally:
                    depth[0] -= 1
                    if depth[0] == 0:
                        spent[label] += time.perf_counter() - start
            return timed
        setattr(owner, name, wrap(original))
    # motions look up time_joint_path by name in their own module
    from cramlite.designators import motions
    motions_original = motions.time_joint_path
    motions.time_joint_path = trajectory.time_joint_path
    try:
        yield spent
    finally:
        motions.time_joint_path = motions_original
        for owner, name, original in originals:
            setattr(owner, name, original)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--trials", type=int, default=7)
    args = parser.parse_args()

    shares: dict[str, list[float]] = collections.defaultdict(list)
    for strategy in ("baseline", "opm"):
        walls, totals, planned = [], [], []
        for seed in range(args.trials):
            start = time.perf_counter()
            with TrialRunner("v1") as runner, timed_parts() as spent:
                result = runner.run(strategy, seed=seed)
            totals.append(time.perf_counter() - start)
            walls.append(result.wall_s)
            planned.append(result.planned_arm_motions)
            assert result.success, result.failures
            for label in dict.fromkeys(label for label, _, _ in PARTS):
                shares[label].append(spent[label] / result.wall_s)
            shares["other (designators, strategy, Python)"].append(
                1 - sum(spent.values()) / result.wall_s)
        first = []  # the first trial of a process: nothing worked out yet (cramlite run)
        for seed in range(args.trials):
            done = subprocess.run([sys.executable, "-m", "cramlite", "run", "v1",
                                   "--strategy", strategy, "--seed", str(seed), "--json"],
                                  capture_output=True, text=True, check=True)
            first.append(json.loads(done.stdout)["wall_s"])
        print(f"v1 trial ({strategy}): wall_s median {statistics.median(walls):.3f} s in a "
              f"new world of this process (min {min(walls):.3f}, max {max(walls):.3f}), with "
              f"world loading {statistics.median(totals):.3f} s; as the first trial of a "
              f"process {statistics.median(first):.3f} s (min {min(first):.3f}, max "
              f"{max(first):.3f}) (n={args.trials}; target <= 0.6 s); "
              f"OMPL arm detours per trial: median {statistics.median(planned)}")
    print("where the wall time goes (median share over the trials above; the timers add "
          "a little):")
    for label, values in shares.items():
        print(f"  {label:<40} {statistics.median(values) * 100:5.1f} %")

    ik_solver = arm_ik("right")
    rng = np.random.default_rng(0)
    targets = [ik_solver.forward(ik_solver.from_q(ik_solver.random_q(rng))) for _ in range(300)]
    times, failures = [], 0
    for target in targets:
        start = time.perf_counter()
        failures += ik_solver.solve(target, rng) is None
        times.append(time.perf_counter() - start)
    print(f"IK solve (reachable, random start): median {statistics.median(times) * 1e3:.2f} ms, "
          f"p90 {np.percentile(times, 90) * 1e3:.2f} ms, {failures}/300 unsolved (target < 5 ms)")

    if True:  # (the v1 kitchen's 2D map)
        scene = PlanningScene(load_setup("v1"))
        planner = BaseMotionPlanner(FootprintChecker(OccupancyMap(
            scene.environment_footprints())))
        queries = {"start -> island (blocked straight line)":
                   ((-0.5, -1.8, math.pi / 2), (-0.3, 1.4, math.pi)),
                   "counter -> island": ((0.80, -0.46, 0.0), (-0.3, 1.4, math.pi)),
                   "around the island corner": ((-0.3, 0.1, 0.0), (-1.95, 1.7, math.pi / 2))}
        for name, (a, b) in queries.items():
            times = []
            for seed in range(21):
                start = time.perf_counter()
                path = planner.plan(a, b, np.random.default_rng(seed))
                times.append(time.perf_counter() - start)
                assert path is not None
            print(f"base plan, {name}: median {statistics.median(times) * 1e3:.1f} ms "
                  "(target < 50 ms)")


if __name__ == "__main__":
    main()
