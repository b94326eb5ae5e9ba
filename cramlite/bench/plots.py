"""Batch plots (PNG): box plots of time and distance per setup and strategy and
aggregated (the source's figures 4.3-4.6), and, with all orders, where each strategy
falls among them. Needs matplotlib (`pip install cramlite[plots]`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.bench.specs import FIXED_ORDER

LABELS = {"robot_time_s": "robot time (s): wall + driving + arm motion",
          "base_path_m": "driven base path (m)", "straight_line_m": "straight-line legs (m)"}


def _values(rows, setup, strategy, measure) -> list[float]:
    out = []
    for r in rows:
        if r["strategy"] == strategy and (setup is None or r["setup"] == setup) \
                and str(r["success"]) == "True":
            try:
                out.append(float(r[measure]))
            except (TypeError, ValueError):
                continue
    return out


def write_plots(rows: Sequence[dict[str, Any]], folder: Path) -> list[Path]:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    written = []
    strategies = sorted({r["strategy"] for r in rows} - {FIXED_ORDER})
    setups = sorted({r["setup"] for r in rows})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for measure in ("robot_time_s", "base_path_m"):
        fig, ax = plt.subplots(figsize=(max(6.0, 1.4 * len(setups) * len(strategies)), 4.5))
        positions, data, tick_pos = [], [], []
        width = 0.8 / max(1, len(strategies))
        for i, setup in enumerate(setups):
            for j, strategy in enumerate(strategies):
                data.append(_values(rows, setup, strategy, measure))
                positions.append(i + (j - (len(strategies) - 1) / 2) * width)
            tick_pos.append(i)
        boxes = ax.boxplot(data, positions=positions, widths=width * 0.9, patch_artist=True,
                           showmeans=True)
        for k, patch in enumerate(boxes["boxes"]):
            patch.set_facecolor(colours[k % len(strategies) % len(colours)])
            patch.set_alpha(0.6)
        ax.set_xticks(tick_pos, setups)
        ax.set_ylabel(LABELS[measure])
        handles = [plt.Rectangle((0, 0), 1, 1, color=colours[j % len(colours)], alpha=0.6)
                   for j in range(len(strategies))]
        ax.legend(handles, strategies, loc="best")
        ax.set_title(f"{LABELS[measure].split(' (')[0]} per setup and strategy")
        written.append(_save(fig, folder / f"{measure}_by_setup.png"))

        fig, ax = plt.subplots(figsize=(2 + 1.5 * len(strategies), 4.5))
        ax.boxplot([_values(rows, None, s, measure) for s in strategies],
                   tick_labels=strategies, showmeans=True)
        ax.set_ylabel(LABELS[measure])
        ax.set_title(f"all setups ({LABELS[measure].split(' (')[0]})")
        written.append(_save(fig, folder / f"{measure}_aggregated.png"))

    ordered = sorted({r["setup"] for r in rows if r["strategy"] == FIXED_ORDER})
    if ordered:
        fig, axes = plt.subplots(1, len(ordered), figsize=(3.2 * len(ordered), 3.8),
                                 squeeze=False)
        for ax, setup in zip(axes[0], ordered, strict=True):
            every = _values(rows, setup, FIXED_ORDER, "base_path_m")
            ax.hist(every, bins=20, color="lightgrey", edgecolor="grey")
            for j, strategy in enumerate(strategies):
                mine = _values(rows, setup, strategy, "base_path_m")
                if mine:
                    ax.axvline(float(np.mean(mine)), color=colours[j % len(colours)], lw=2,
                               label=strategy)
            ax.set_title(f"{setup}: {len(every)} orders")
            ax.set_xlabel("driven base path (m)")
        axes[0][0].set_ylabel("orders")
        axes[0][-1].legend(loc="best")
        written.append(_save(fig, folder / "all_orders_base_path.png"))
    return written


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
