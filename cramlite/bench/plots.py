"""Batch plots (PNG): box plots of time and distance per setup and strategy and
aggregated (the source's figures 4.3-4.6), and, with all orders, where each strategy
falls among them. Needs matplotlib (`pip install cramlite[plots]`).

Every box plot says what it shows: the legend names each strategy's colour and what the
box (quartiles), the line (median), the triangle (mean), the whiskers and the circles
(outliers) are, and each box is labelled with its n (successful trials).
"""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.bench.labels import base_name
from cramlite.bench.specs import FIXED_ORDER

LABELS = {"robot_time_s": "robot time (s): driving + arm motion",
          "base_path_m": "driven base path (m)", "straight_line_m": "straight-line legs (m)"}
#: Colours of the strategies, in sorted order (matplotlib's default cycle).
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")
#: What the parts of a box plot mean (the page's caption says the same).
BOX_LEGEND = ("box: middle half of the trials (25-75 %)", "line: median",
              "triangle: mean", "whiskers: up to 1.5 x the box height; circles beyond",
              "fewer than 5 trials: each trial a dot")


BOX_STYLE: dict[str, Any] = {
    "showmeans": True, "medianprops": {"color": "black", "linewidth": 1.5},
    "meanprops": {"marker": "^", "markerfacecolor": "white", "markeredgecolor": "black"},
    "flierprops": {"marker": "o", "markerfacecolor": "none", "markeredgecolor": "black"}}


#: The built-in strategies keep these colours in every report.
FIXED_COLOURS = {"opm": PALETTE[0], "baseline": PALETTE[1], "random": PALETTE[2],
                 "nearest": PALETTE[3], "opm-two-step": PALETTE[4], "optimal": PALETTE[5]}


def strategy_colours(strategies: Sequence[str]) -> dict[str, str]:
    """One colour per strategy, the same in every report: the built-ins' fixed ones; any
    other name's from a hash of it (the next free colour where two names of one report
    would share one)."""
    import zlib

    out: dict[str, str] = {}
    for name in sorted(strategies, key=lambda n: (base_name(n) not in FIXED_COLOURS, n)):
        base = base_name(name)  # (opm@kinematic: opm's colour, where it is free)
        spare = len(PALETTE) - len(FIXED_COLOURS)  # (the colours no built-in has)
        first = PALETTE.index(FIXED_COLOURS[base]) if base in FIXED_COLOURS else \
            len(FIXED_COLOURS) + zlib.crc32(base.encode()) % spare
        used = set(out.values())
        for k in range(len(PALETTE)):
            colour = PALETTE[(first + k) % len(PALETTE)]
            if colour not in used or len(used) >= len(PALETTE):
                out[name] = colour
                break
    return out


#: Fewer trials than this are drawn as points (and their mean), not as a box.
MIN_BOX_N = 5


def _boxes_or_points(ax, data: list[list[float]], positions: list[float], width: float,
                     colours: list[str]) -> None:
    """A box per group of at least MIN_BOX_N values; the values themselves (and the mean
    triangle) where there are fewer: a box of two trials says nothing a point does not."""
    big = [k for k, values in enumerate(data) if len(values) >= MIN_BOX_N]
    if big:
        boxes = ax.boxplot([data[k] for k in big], positions=[positions[k] for k in big],
                           widths=width, patch_artist=True, **BOX_STYLE)
        for patch, k in zip(boxes["boxes"], big, strict=True):
            patch.set_facecolor(colours[k])
            patch.set_alpha(0.6)
    for k, values in enumerate(data):
        if values and len(values) < MIN_BOX_N:
            offsets = np.linspace(-width / 4, width / 4, len(values)) if len(values) > 1 \
                else np.zeros(1)
            ax.scatter(positions[k] + offsets, values, s=28, color=colours[k],
                       edgecolors="black", linewidths=0.6, zorder=3)
            ax.scatter([positions[k]], [float(np.mean(values))], marker="^", s=40,
                       facecolors="white", edgecolors="black", zorder=4)


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


def write_plots(rows: Sequence[dict[str, Any]], folder: Path,
                also_to: Path | None = None) -> list[Path]:
    """The bench's plots (PNG) in `folder`, and copies in `also_to` if given (the report
    draws them for its page and for the bench's folder at once); the paths in `folder`."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    strategies = sorted({r["strategy"] for r in rows} - {FIXED_ORDER})
    setups = sorted({r["setup"] for r in rows})
    colours = strategy_colours(strategies)
    for measure in ("robot_time_s", "base_path_m") if strategies else ():
        fig, ax = plt.subplots(figsize=(max(7.0, 1.4 * len(setups) * len(strategies)), 4.8))
        positions, data, tick_pos, owners = [], [], [], []
        width = 0.8 / max(1, len(strategies))
        for i, setup in enumerate(setups):
            for j, strategy in enumerate(strategies):
                data.append(_values(rows, setup, strategy, measure))
                positions.append(i + (j - (len(strategies) - 1) / 2) * width)
                owners.append(strategy)
            tick_pos.append(i)
        _boxes_or_points(ax, data, positions, width * 0.9, [colours[o] for o in owners])
        _label_n(ax, positions, data)
        ax.set_xticks(tick_pos, setups)
        ax.set_xlabel("setup")
        ax.set_ylabel(LABELS[measure])
        _legend(ax, [(s, colours[s]) for s in strategies])
        ax.set_title(f"{LABELS[measure].split(' (')[0]} per setup and strategy "
                     "(successful trials; n per box above it)", pad=16)
        written.append(_save(fig, folder / f"{measure}_by_setup.png"))

        fig, ax = plt.subplots(figsize=(4.5 + 1.5 * len(strategies), 4.8))
        data = [_values(rows, None, s, measure) for s in strategies]
        places = list(range(1, len(strategies) + 1))
        _boxes_or_points(ax, data, places, 0.5, [colours[s] for s in strategies])
        ax.set_xticks(places, strategies)
        _label_n(ax, places, data)
        ax.set_ylabel(LABELS[measure])
        _legend(ax, [])
        ax.set_title(f"all setups ({LABELS[measure].split(' (')[0]})", pad=16)
        written.append(_save(fig, folder / f"{measure}_aggregated.png"))

    ordered = sorted({r["setup"] for r in rows if r["strategy"] == FIXED_ORDER})
    if ordered:
        fig, axes = plt.subplots(1, len(ordered), figsize=(3.4 * len(ordered) + 0.6, 3.9),
                                 squeeze=False)
        for ax, setup in zip(axes[0], ordered, strict=True):
            every = _values(rows, setup, FIXED_ORDER, "base_path_m")
            ax.hist(every, bins=20, color="lightgrey", edgecolor="grey",
                    label="all orders (fixed)")
            for strategy in strategies:
                mine = _values(rows, setup, strategy, "base_path_m")
                if mine:
                    ax.axvline(float(np.mean(mine)), color=colours[strategy], lw=2,
                               label=f"{strategy} (mean of {len(mine)})")
            ax.set_title(f"{setup}: {len(every)} orders")
            ax.set_xlabel("driven base path (m)")
            ax.legend(loc="best", fontsize=7)
        axes[0][0].set_ylabel("orders")
        written.append(_save(fig, folder / "all_orders_base_path.png"))
    if also_to is not None:
        for path in written:
            shutil.copyfile(path, also_to / path.name)
    return written


def _label_n(ax: Any, positions: Sequence[float], data: Sequence[Sequence[float]]) -> None:
    """'n=K' under each box (K: the values in it)."""
    transform = ax.get_xaxis_transform()
    for x, values in zip(positions, data, strict=True):
        ax.text(x, 1.01, f"n={len(values)}", transform=transform, ha="center", va="bottom",
                fontsize=7, color="#444444")


def _legend(ax: Any, strategies: Sequence[tuple[str, str]]) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=c, alpha=0.6, label=s)
               for s, c in strategies]
    handles += [plt.Rectangle((0, 0), 1, 1, facecolor="white", edgecolor="black",
                              label=BOX_LEGEND[0]),
                Line2D([], [], color="black", linewidth=1.5, label=BOX_LEGEND[1]),
                Line2D([], [], marker="^", linestyle="none", markerfacecolor="white",
                       markeredgecolor="black", label=BOX_LEGEND[2]),
                Line2D([], [], marker="o", linestyle="none", markerfacecolor="none",
                       markeredgecolor="black", label=BOX_LEGEND[3]),
                Line2D([], [], marker="o", linestyle="none", markerfacecolor="grey",
                       markeredgecolor="black", label=BOX_LEGEND[4])]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7,
              frameon=False)


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    # (bbox "tight": a title wider than its axes is kept whole, not clipped at the edge)
    fig.savefig(path, dpi=110, metadata={"Software": None}, bbox_inches="tight",
                pad_inches=0.15)
    plt.close(fig)
    return path
