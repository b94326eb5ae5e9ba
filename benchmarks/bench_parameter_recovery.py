"""Parameter recovery (#28): does `fit` recover the k and c that generated the data?

20 parameter sets drawn from the Table 3.4 grid (strong k 0.0-0.9, mid k = strong + 0.1,
food k 1.1-2.0, c 1.0-2.0), each simulated on the table-setting tasks (`cramlite
simulate`: the recorded items, positions and start positions, orders drawn by a softmax
over the OPM's costs at --temperature) with 3 seeds, then fitted by the grid search of
`cramlite fit` (xy): by default by the maximum likelihood of the choices under the
softmax they were drawn with (`--metric likelihood`), or by the thesis's criterion
(`--metric expected-ape`). A parameter is recovered when the fit's best value is within
one grid step (0.1) of the generating one. Where the best is a plateau (values that change
no decision in these tasks fit exactly as well), the plateau is reported too.

    python benchmarks/bench_parameter_recovery.py [--episodes 744] [--temperature 0.2]
        [--metric likelihood|expected-ape] [--plot docs/images/parameter_recovery.png]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from cramlite.evaluation.data import load_episodes
from cramlite.evaluation.fit import PARAM_NAMES
from cramlite.evaluation.recovery import (
    EPISODES_PER_TASK,
    RECOVERY_TEMPERATURE,
    recovery_study,
    recovery_table,
)
from cramlite.resources import resolve_data_path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--like", default="table-setting")
    parser.add_argument("--sets", type=int, default=20)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--episodes", type=int, default=None,
                        help=f"default {EPISODES_PER_TASK} per recorded episode")
    parser.add_argument("--temperature", type=float, default=RECOVERY_TEMPERATURE)
    parser.add_argument("--metric", default="likelihood",
                        choices=("likelihood", "expected-ape", "ape"))
    parser.add_argument("--plot", help="write the recovery plot here (PNG)")
    args = parser.parse_args()
    like, _ = load_episodes(resolve_data_path(args.like))
    started = time.perf_counter()
    episodes = args.episodes or EPISODES_PER_TASK * len(like)
    runs = recovery_study(like, args.sets, args.seeds, episodes, args.temperature,
                          metric=args.metric)
    seconds = time.perf_counter() - started
    print(f"{args.sets} parameter sets x {args.seeds} seeds, {episodes} episodes like "
          f"{args.like}, temperature {args.temperature}, fitted by {args.metric}: "
          f"{seconds:.1f} s")
    print("| parameter | recovered within 0.1 | on a plateau that holds it | mean plateau width |")
    print("|---|---|---|---|")
    for row in recovery_table(runs):
        print(f"| {row['parameter']} | {100 * row['recovered']:.0f} % | "
              f"{100 * row['on_plateau']:.0f} % | {row['plateau_width']:.2f} |")
    every = np.mean([all(r.recovered(n) for n in PARAM_NAMES) for r in runs])
    kc = np.mean([all(r.recovered(n) for n in ("strong_k", "mid_k", "c")) for r in runs])
    print(f"every parameter recovered: {100 * every:.0f} % of fits; strong k, mid k and c: "
          f"{100 * kc:.0f} %")
    if args.plot:
        plot(runs, args.plot, args.temperature, episodes, args.metric)
        print(f"wrote {args.plot}")


def plot(rows, path: str, temperature: float, episodes: int, metric: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(PARAM_NAMES), figsize=(13, 3.6))
    jitter = np.random.default_rng(0)
    for ax, name in zip(axes, PARAM_NAMES, strict=True):
        truth = np.array([r.truth[name] for r in rows])
        best = np.array([r.best[name] for r in rows])
        lo = np.array([r.plateau[name][0] for r in rows])
        hi = np.array([r.plateau[name][1] for r in rows])
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
    fitted = "maximum likelihood" if metric == "likelihood" else metric
    fig.suptitle(f"Parameter recovery: OPM on the table-setting tasks, {episodes} episodes, "
                 f"softmax temperature {temperature}, fitted by {fitted}", fontsize=10)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    main()
