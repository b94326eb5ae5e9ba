"""Instructions a trial costs, counted by valgrind: a figure that does not move with the
machine's load, where wall-clock medians on this 2-core machine move by 1.5x from one hour
to the next (docs/benchmarks.md). Use it to see whether a change of a few per cent helps.

For each setup: a process that loads the setup and runs the trials of seeds 0 and 1,
against one that runs `--warm` more after them (seeds 2, 3, ...); the difference divided
by `--warm` is a warm trial's instructions (the figures of docs/benchmarks.md). Also a
whole `cramlite run SETUP` process (import, load, one trial, summary). Kinematic backend,
the OPM, PYTHONHASHSEED=0 (sets iterate alike in every run).
Each process runs 30-60 times slower under valgrind: a warm c1 trial takes ~1 min.

    python benchmarks/bench_instructions.py [--setups v1,c1] [--warm 2] [--no-fresh]

Needs valgrind (Debian/Ubuntu: apt install valgrind).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

BIN = Path(sys.executable).parent
CRAMLITE = [str(BIN / "cramlite")] if (BIN / "cramlite").exists() else \
    [sys.executable, "-m", "cramlite"]
TRIALS = """
import sys
from cramlite.trial import TrialRunner
with TrialRunner(sys.argv[1], backend="kinematic") as runner:
    for seed in range(int(sys.argv[2]) + 1):
        runner.run("opm", seed=seed)
"""


def instructions(command: list[str]) -> int:
    """Instructions the command's process executes (valgrind's cachegrind, no cache
    simulation: only the count)."""
    env = {**os.environ, "PYTHONHASHSEED": "0"}
    done = subprocess.run(["valgrind", "--tool=cachegrind", "--cache-sim=no",
                           "--cachegrind-out-file=/dev/null", *command],
                          capture_output=True, text=True, env=env)
    if done.returncode != 0:
        raise SystemExit(f"bench_instructions: {' '.join(command)} failed "
                         f"(exit {done.returncode}):\n{done.stderr[-2000:]}")
    found = re.search(r"I\s+refs:\s+([\d,]+)", done.stderr)
    if found is None:
        raise SystemExit("bench_instructions: valgrind printed no instruction count")
    return int(found.group(1).replace(",", ""))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--setups", default="v1,c1")
    parser.add_argument("--warm", type=int, default=2, help="warm trials counted (>= 1)")
    parser.add_argument("--no-fresh", action="store_true",
                        help="skip the whole `cramlite run` process")
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        raise SystemExit("bench_instructions: valgrind is not installed "
                         "(Debian/Ubuntu: apt install valgrind)")
    if args.warm < 1:
        raise SystemExit("bench_instructions: --warm must be at least 1")
    from cramlite.errors import UserInputError
    from cramlite.world import load_setup

    for setup in args.setups.split(","):  # (named before minutes under valgrind)
        try:
            load_setup(setup)
        except UserInputError as exc:
            raise SystemExit(f"bench_instructions: {exc}") from None
    for setup in args.setups.split(","):
        first = instructions([sys.executable, "-c", TRIALS, setup, "1"])
        more = instructions([sys.executable, "-c", TRIALS, setup, str(1 + args.warm)])
        warm = (more - first) / args.warm
        print(f"{setup}: load and the trials of seeds 0-1 {first / 1e6:,.0f} M instructions; "
              f"a warm trial (seeds 2-{1 + args.warm}) {warm / 1e6:,.0f} M", flush=True)
        if not args.no_fresh:
            fresh = instructions([*CRAMLITE, "run", setup, "--backend", "kinematic",
                                  "--strategy", "opm"])
            print(f"{setup}: a fresh `cramlite run {setup}` {fresh / 1e6:,.0f} M", flush=True)


if __name__ == "__main__":
    main()
