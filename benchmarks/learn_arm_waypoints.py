"""Learn the arm waypoints the arm planner tries before OMPL (cramlite/motion/arm_waypoints.json).

Runs the shipped setups with the waypoints switched off and records every arm motion OMPL
was asked to plan (an arm's seven joints) with the work it spent (states checked plus exact
pair tests: the same on any machine). The vertices of the paths OMPL found are the
candidate waypoints; each is tried on every recorded motion of its arm as the planner
would try it (`ArmMotionPlanner._via_waypoint`: both legs straight and free at every
step). Waypoints are then chosen greedily, each covering the most OMPL work not yet
covered, until one would cover less than `--min-share` of it. Deterministic: the trials'
seeds are fixed, the work is counted, not timed.

    python benchmarks/learn_arm_waypoints.py [--seeds 1-4] [--out FILE]

Re-run it when the robot, the kitchen or the planner changes what OMPL is asked; the file
it writes lists where it was learned.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cramlite.errors import UserInputError
from cramlite.motion import arm_planner
from cramlite.motion.arm_planner import WAYPOINTS_FILE, ArmMotionPlanner
from cramlite.motion.ik import ARM_JOINTS
from cramlite.trial import TrialRunner

SETUPS = ("v1", "v2", "v3", "v4", "v5", "c1", "c2", "c3")
STRATEGIES = ("opm", "baseline")


@dataclass
class Query:
    """One coarse OMPL search: its check, ends, steps, the work it spent, its path."""

    planner: ArmMotionPlanner
    scene: object
    names: tuple[str, ...]
    start: np.ndarray
    goal: np.ndarray
    steps: np.ndarray
    work: int
    vertices: np.ndarray | None


def record(setups: list[str], seeds: list[int]) -> list[Query]:
    """The OMPL searches of an arm's seven joints in the trials, waypoints switched off."""
    queries: list[Query] = []
    search = ArmMotionPlanner._ompl

    def recorded(self, scene, start, goal, steps, seed, every, margin):
        work = scene.checks + scene.narrow
        vertices = search(self, scene, start, goal, steps, seed, every, margin)
        names = tuple(scene.joints)
        if margin and len(names) == len(ARM_JOINTS):
            queries.append(Query(self, scene, names, start.copy(), goal.copy(), steps.copy(),
                                 scene.checks + scene.narrow - work,
                                 None if vertices is None else vertices.copy()))
        return vertices

    learned = arm_planner.arm_waypoints
    ArmMotionPlanner._ompl = recorded
    arm_planner.arm_waypoints = lambda: {}  # (OMPL asked every time, as with none)
    try:
        for setup in setups:
            with TrialRunner(setup, backend="kinematic") as runner:
                for seed in seeds:
                    for strategy in STRATEGIES:
                        runner.run(strategy, seed=seed)
    finally:
        ArmMotionPlanner._ompl = search
        arm_planner.arm_waypoints = learned
    return queries



def tidy(names: tuple[str, ...], q: np.ndarray, planner: ArmMotionPlanner) -> np.ndarray:
    """A waypoint as stored: continuous joints within (-pi, pi], 6 decimals."""
    out = q.copy()
    for i, name in enumerate(names):
        if name in planner.limits.continuous:
            out[i] = math.remainder(out[i], 2 * math.pi)
    return np.round(out, 6)


def solves(query: Query, waypoint: np.ndarray) -> bool:
    return query.planner._via_waypoint(query.scene, query.names, query.start, query.goal,
                                       query.steps, (waypoint,)) is not None


def choose(queries: list[Query], min_share: float,
           ) -> tuple[list[tuple[tuple[str, ...], np.ndarray]], float]:
    """The waypoints, greedily by OMPL work covered, and the share of the work covered."""
    candidates = [(q.names, tidy(q.names, v, q.planner)) for q in queries
                  if q.vertices is not None for v in q.vertices[1:-1]]
    work = np.array([q.work for q in queries], dtype=float)
    covers = np.array([[names == q.names and solves(q, w) for q in queries]
                       for names, w in candidates], dtype=bool).reshape(len(candidates),
                                                                        len(queries))
    covered = np.zeros(len(queries), dtype=bool)
    chosen = []
    while len(candidates):
        gain = (covers & ~covered) @ work
        best = int(np.argmax(gain))
        if gain[best] <= 0 or gain[best] < min_share * work.sum():
            break
        chosen.append(candidates[best])
        covered |= covers[best]
    return chosen, float(work[covered].sum() / max(work.sum(), 1.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--setups", default=",".join(SETUPS))
    parser.add_argument("--seeds", default="1-4", help="a range, e.g. 1-4")
    parser.add_argument("--min-share", type=float, default=0.005,
                        help="stop when a waypoint would cover less of the OMPL work")
    parser.add_argument("--out", type=Path, default=None,
                        help="where to write (default: the shipped file, and only when "
                             "learned from the default setups and seeds)")
    args = parser.parse_args()
    if not 0 < args.min_share < 1:
        parser.error(f"--min-share: expected a share between 0 and 1, not {args.min_share}")
    if args.out is None:
        if args.setups != ",".join(SETUPS) or args.seeds != "1-4":
            parser.error("give --out: waypoints learned from other setups or seeds would "
                         f"replace the shipped {WAYPOINTS_FILE.name}")
        args.out = WAYPOINTS_FILE
    first, _, last = args.seeds.partition("-")
    if not (first.isdigit() and (last.isdigit() or not last)) or int(last or first) < int(first):
        parser.error(f"--seeds: expected a range such as 1-4, not {args.seeds!r}")
    seeds = list(range(int(first), int(last or first) + 1))
    setups = args.setups.split(",")
    try:
        queries = record(setups, seeds)
    except UserInputError as exc:  # (a setup that is not there, say)
        parser.error(str(exc))
    chosen, share = choose(queries, args.min_share)
    found = sum(q.vertices is not None for q in queries)
    print(f"{len(queries)} OMPL searches ({found} found a path), {len(chosen)} waypoints "
          f"covering {share:.0%} of their work")
    arms: dict[str, list[list[float]]] = {"r": [], "l": []}
    for names, waypoint in chosen:
        arms[names[0][:1]].append([float(v) for v in waypoint])
    about = {"about": "Arm waypoints the arm planner tries before OMPL, in order; joints: "
                      + ", ".join(ARM_JOINTS) + " (rad). Written by "
                      "benchmarks/learn_arm_waypoints.py.",
             "learned_from": {"setups": setups, "seeds": seeds,
                              "strategies": list(STRATEGIES), "searches": len(queries),
                              "work_covered": round(share, 3)}}
    lines = [json.dumps(about, indent=1)[:-2] + ',\n "arms": {']
    for k, (prefix, waypoints) in enumerate(arms.items()):
        rows = ",\n".join(f"   {json.dumps(w)}" for w in waypoints)
        lines.append(f'  "{prefix}": [\n{rows}\n  ]' + ("," if k < len(arms) - 1 else ""))
    lines.append(" }\n}\n")
    text = "\n".join(lines)
    json.loads(text)  # (well formed)
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
