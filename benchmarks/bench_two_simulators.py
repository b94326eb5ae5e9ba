"""Two simulators, one answer: every setup x strategy on pybullet and on mujoco (and the
kinematic backend for speed), with what each simulator measured side by side, and the
MuJoCo backend's time broken down (loading, physics steps, offscreen frames).

    python benchmarks/bench_two_simulators.py [--setups v1,...,c3] [--strategies opm,baseline]

Prints, per trial: both orders and success, the largest gap between where the two left an
item (the agreement asked for: < 1 cm), the largest distance of an item from its target in
each, wall_s on kinematic, pybullet and mujoco, the deepest contact each simulator saw while
items settled; then the breakdown and the verdict.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from cramlite.trial import TrialRunner

SETUPS = "v1,v2,v3,v4,v5,c1,c2,c3"


def _trials(backend: str, setups: list[str], strategies: list[str]) -> dict:
    out = {}
    for setup in setups:
        start = time.perf_counter()
        with TrialRunner(setup, backend=backend) as runner:
            loaded = time.perf_counter() - start
            for strategy in strategies:
                result = runner.run(strategy, seed=0)
                out[(setup, strategy)] = (result, loaded,
                                          result.simulator.get("physics_steps", 0))
    return out


def _frame_ms(setup: str, frames: int = 30) -> float:
    from cramlite.backends.mujoco.render import Renderer
    from cramlite.backends.mujoco.world import MujocoWorld
    from cramlite.render.camera import REPLAY_CAMERA, camera
    from cramlite.world.setup import load_setup

    with MujocoWorld(load_setup(setup)) as world, Renderer(world, 400, 300) as renderer:
        view = camera(REPLAY_CAMERA, REPLAY_CAMERA)
        renderer.image(view)  # (the first frame makes the GL context)
        start = time.perf_counter()
        for _ in range(frames):
            renderer.image(view)
        return (time.perf_counter() - start) / frames * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--setups", default=SETUPS)
    parser.add_argument("--strategies", default="opm,baseline")
    args = parser.parse_args()
    setups, strategies = args.setups.split(","), args.strategies.split(",")
    runs = {b: _trials(b, setups, strategies) for b in ("kinematic", "pybullet", "mujoco")}
    agree = True
    ratios = []
    for key in runs["mujoco"]:
        py, _, _ = runs["pybullet"][key]
        mj, loaded, steps = runs["mujoco"][key]
        kin = runs["kinematic"][key][0]
        gap = max(np.linalg.norm(np.subtract(mj.items[n]["position"], py.items[n]["position"]))
                  for n in mj.items)
        off = {b: max(r.items[n].get("off_target_m", 0.0) for n in r.items)
               for b, r in (("pybullet", py), ("mujoco", mj))}
        same = py.order == mj.order and py.success == mj.success and gap < 0.01
        agree &= same and py.success and mj.success
        ratios.append(mj.wall_s / kin.wall_s)
        print(f"{key[0]} {key[1]:8s} orders {'same' if py.order == mj.order else 'DIFFER'}, "
              f"success {py.success}/{mj.success}, items within {gap * 100:.2f} cm of each "
              f"other, off target at most {off['pybullet'] * 100:.2f} / {off['mujoco'] * 100:.2f}"
              f" cm; wall_s kinematic {kin.wall_s:.2f}, pybullet {py.wall_s:.2f}, mujoco "
              f"{mj.wall_s:.2f} (load {loaded:.2f} s, {steps} physics steps); deepest "
              f"contact while settling {py.simulator.get('deepest_contact_m', 0) * 1000:.2f}"
              f" / {mj.simulator.get('deepest_contact_m', 0) * 1000:.2f} mm")
    print(f"mujoco wall_s / kinematic wall_s: median {statistics.median(ratios):.2f}, "
          f"max {max(ratios):.2f}")
    print(f"MuJoCo offscreen frame (400 x 300): {_frame_ms(setups[0]):.1f} ms")
    print("the two simulators agree on every trial" if agree else "THEY DISAGREE (above)")


if __name__ == "__main__":
    main()
