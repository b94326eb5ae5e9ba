"""Parameter recovery (#28): does `fit` recover the k and c that generated the data?

20 parameter sets drawn from the Table 3.4 grid (strong k 0.0-0.9, mid k = strong + 0.1,
food k 1.1-2.0, c 1.0-2.0), each simulated on the table-setting tasks (`cramlite
simulate`: the recorded items, positions and start positions, orders drawn by a softmax
over the OPM's costs at --temperature) with 3 seeds, then fitted by the grid search of
`cramlite fit` (expected APE, xy). A parameter is recovered when the fit's best value is
within one grid step (0.1) of the generating one. Where the best is a plateau (values
that change no decision in these tasks fit exactly as well), the plateau is reported too.

    python benchmarks/bench_parameter_recovery.py [--episodes 372] [--temperature 0.05]
        [--plot docs/images/parameter_recovery.png]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from cramlite.evaluation.data import load_episodes, parse_row
from cramlite.evaluation.fit import PARAM_NAMES, fit, source_grid
from cramlite.evaluation.options import DEFAULT_TEMPERATURE
from cramlite.evaluation.simulate import episode_row, simulate
from cramlite.resources import resolve_data_path

STEP = 0.1 + 1e-9


def recover(like, params: dict[str, float], episodes: int, temperature: float, seed: int):
    drawn = simulate(like, episodes, "opm", params, temperature, seed)
    # (through the published format, as `cramlite simulate` writes it and `fit` reads it)
    synthetic = [parse_row(episode_row(e)) for e in drawn]
    result = fit(synthetic, "opm", ("xy",), "expected-ape")
    _, index = result.best("xy")
    return result.params(index), result.tied_best("xy")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--like", default="table-setting")
    parser.add_argument("--sets", type=int, default=20)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--episodes", type=int, default=372)
    parser.add_argument("--temperature", type=float, default=DEFAULT_TEMPERATURE)
    parser.add_argument("--plot", help="write the recovery plot here (PNG)")
    args = parser.parse_args()
    like, _ = load_episodes(resolve_data_path(args.like))
    grid = source_grid()
    picks = np.random.default_rng(2026).choice(len(grid), size=args.sets, replace=False)
    started = time.perf_counter()
    rows = []
    for g in picks:
        truth = dict(zip(PARAM_NAMES, map(float, grid[g]), strict=True))
        for seed in range(args.seeds):
            best, tied = recover(like, truth, args.episodes, args.temperature, seed)
            rows.append((truth, best, tied))
    seconds = time.perf_counter() - started
    print(f"{args.sets} parameter sets x {args.seeds} seeds, {args.episodes} episodes like "
          f"{args.like}, temperature {args.temperature}: {seconds:.1f} s")
    print("| parameter | recovered within 0.1 | on a plateau that holds it | mean plateau width |")
    print("|---|---|---|---|")
    for name in PARAM_NAMES:
        hit = np.mean([abs(b[name] - t[name]) <= STEP for t, b, _ in rows])
        held = np.mean([tied[name][0] - STEP <= t[name] <= tied[name][1] + STEP
                        for t, _, tied in rows])
        width = np.mean([tied[name][1] - tied[name][0] for _, _, tied in rows])
        print(f"| {name} | {100 * hit:.0f} % | {100 * held:.0f} % | {width:.2f} |")
    every = np.mean([all(abs(b[n] - t[n]) <= STEP for n in PARAM_NAMES) for t, b, _ in rows])
    kc = np.mean([all(abs(b[n] - t[n]) <= STEP for n in ("strong_k", "mid_k", "c"))
                  for t, b, _ in rows])
    print(f"every parameter recovered: {100 * every:.0f} % of fits; strong k, mid k and c: "
          f"{100 * kc:.0f} %")
    if args.plot:
        plot(rows, args.plot, args.temperature, args.episodes)
        print(f"wrote {args.plot}")


def plot(rows, path: str, temperature: float, episodes: int) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(PARAM_NAMES), figsize=(13, 3.6))
    jitter = np.random.default_rng(0)
    for ax, name in zip(axes, PARAM_NAMES, strict=True):
        truth = np.array([t[name] for t, _, _ in rows])
        best = np.array([b[name] for _, b, _ in rows])
        lo = np.array([tied[name][0] for _, _, tied in rows])
        hi = np.array([tied[name][1] for _, _, tied in rows])
        x = truth + jitter.uniform(-0.025, 0.025, len(truth))
        ax.vlines(x, lo, hi, color="tab:blue", alpha=0.35, linewidth=3,
                  label="fits as well (plateau)")
        ax.scatter(x, best, s=14, color="tab:blue", label="fit's best", zorder=3)
        span = (min(truth.min(), lo.min()) - 0.1, max(truth.max(), hi.max()) + 0.1)
        ax.plot(span, span, color="grey", linewidth=1)
        ax.fill_between(span, np.array(span) - 0.1, np.array(span) + 0.1, color="grey",
                        alpha=0.15, label="within 0.1")
        ax.set_title(name)
        ax.set_xlabel("generating value")
    axes[0].set_ylabel("recovered value")
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"Parameter recovery: OPM on the table-setting tasks, {episodes} episodes, "
                 f"softmax temperature {temperature}", fontsize=10)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    main()
