"""The report's pictures (matplotlib, PNG): per setup a top-down map with each strategy's
driven paths and fetch order, and per trial a timeline of its task tree."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cramlite.report.trials import Bar, bars, ok
from cramlite.world.map_labels import badge_candidates, movable, settle_labels
from cramlite.world.topdown import Layout, draw_layout

#: Colours of the actions on timelines (others: ACTION_OTHER).
ACTION_COLOURS = {"TransportAction": "#e3e3e3", "FetchAction": "#e3e3e3",
                  "DeliverAction": "#d5d5d5", "NavigateAction": "#4e79a7",
                  "PickUpAction": "#59a14f", "PlaceAction": "#f28e2b",
                  "OpenAction": "#b07aa1", "CloseAction": "#9c755f",
                  "ParkArmsAction": "#bab0ac", "MoveTorsoAction": "#edc948"}
ACTION_OTHER = "#76b7b2"
FAILED = "#d62728"
DPI = 100


def pyplot():
    """matplotlib's pyplot on the Agg backend (imported on first use: it is slow)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: The resolution maps are saved at (labels are placed for it).
MAP_DPI = 125


def _save(fig: Any, path: Path, dpi: int = DPI) -> Path:
    plt = pyplot()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, metadata={"Software": None})
    plt.close(fig)
    return path


def setup_map(layout: Layout, rows: Sequence[dict[str, Any]], strategies: Sequence[str],
              colours: dict[str, str], highlighted: dict[str, dict[str, Any]],
              path: Path) -> Path:
    """One panel per strategy: the kitchen, every trial's driven path faint, the
    highlighted trial's bold with its fetch order numbered at the items, and a red cross
    where a failed trial stopped."""
    return _save(setup_map_figure(layout, rows, strategies, colours, highlighted), path,
                 dpi=MAP_DPI)


def setup_map_figure(layout: Layout, rows: Sequence[dict[str, Any]],
                     strategies: Sequence[str], colours: dict[str, str],
                     highlighted: dict[str, dict[str, Any]]) -> Any:
    """The figure `setup_map` saves (its text placed for the dpi it is saved at)."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    columns = min(2, max(1, len(strategies)))
    lines = math.ceil(len(strategies) / columns) or 1
    fig, axes = plt.subplots(lines, columns, figsize=(5.2 * columns, 5.3 * lines + 0.6),
                             squeeze=False, layout="constrained")
    for ax in axes.flat[len(strategies):]:
        ax.axis("off")
    for ax, strategy in zip(axes.flat, strategies, strict=False):
        colour = colours[strategy]
        draw_layout(ax, layout, legend=False, font_size=7.5)
        mine = sorted((r for r in rows if r["strategy"] == strategy),
                      key=lambda r: int(r["trial"]))
        best = highlighted.get(strategy)
        for row in mine:
            if row is best:
                continue
            xy = row.get("driven_path") or []
            if len(xy) > 1:
                ax.plot(*zip(*xy, strict=True), color=colour, alpha=0.22, linewidth=1.0,
                        zorder=4)
            for x, y in failed_spots(layout, row):
                ax.plot(x, y, marker="x", color=FAILED, markersize=9, markeredgewidth=1.8,
                        alpha=0.8, zorder=10)
        title = f"{strategy}: no trial yet"
        if best is not None:
            _highlight(ax, layout, best, colour)
            status = "succeeded" if ok(best) else "FAILED"
            title = (f"{strategy}, trial {best['trial']} ({status}, bold; "
                     f"{len(mine)} trial{'s' * (len(mine) != 1)} in all)\n"
                     + _wrap(" ".join(f"{k}. {n}" for n, k in fetch_labels(best)) or
                             "no item fetched", 60))
        ax.set_title(title, fontsize=9, color=colour if best is not None else "black")
    handles = [Line2D([], [], color=colours[s], linewidth=2.2,
                      label=f"{s}: driven path (light: early, full colour: late)")
               for s in strategies]
    handles += [Line2D([], [], color="grey", alpha=0.35, linewidth=1,
                       label="other trials (faint)"),
                Line2D([], [], color="grey", linestyle="--", linewidth=1.4,
                       label="straight legs (no driven path recorded)"),
                Line2D([], [], marker="o", linestyle="none", markerfacecolor="white",
                       markeredgecolor="grey", markersize=9,
                       label="n = fetched n-th (bold trial); 2a, 2b: carried together "
                             "on trip 2"),
                Line2D([], [], marker="x", linestyle="none", color=FAILED,
                       label="what a failed trial could not do (item, drawer)")]
    from cramlite.world.topdown import legend_handles

    fig.legend(handles=handles + legend_handles(), loc="outside lower center",
               ncol=3, fontsize=8, frameon=False)
    fig.set_dpi(MAP_DPI)
    settle_labels(fig)
    return fig


def fetch_labels(row: dict[str, Any]) -> list[tuple[str, str]]:
    """(item, its number on the map) in fetch order: 1, 2, 3... or, where a trip carried
    several items (`--carry 2`), the trip's number and a letter per item: 1a, 1b, 2a..."""
    order = str(row.get("order") or "").split()
    trips = row.get("trips") or []
    if isinstance(trips, str):
        from cramlite.safe_json import parse_json

        try:
            trips = parse_json(trips) if trips else []
        except ValueError:
            trips = []
    if not isinstance(trips, list) or not any(isinstance(t, list) and len(t) > 1
                                              for t in trips):
        return [(name, str(k)) for k, name in enumerate(order, 1)]
    out = []
    for k, trip in enumerate(trips, 1):
        names = [str(n) for n in trip] if isinstance(trip, list) else []
        out += [(name, f"{k}{'abcdefgh'[i]}" if len(names) > 1 else str(k))
                for i, name in enumerate(names[:8])]
    return out


def _highlight(ax: Any, layout: Layout, row: dict[str, Any], colour: str) -> None:
    """The bold path (or the straight legs when no path was recorded), the numbers of
    the fetch order at the items, a cross if it failed."""
    xy = row.get("driven_path") or []
    order = row["order"].split()
    spots = {s.name: (s.x, s.y) for s in layout.items}
    targets = {s.name: (s.x, s.y) for s in layout.targets}
    if len(xy) > 1:
        _path_in_sequence(ax, xy, colour)
        _arrows(ax, xy, colour)
    else:  # older rows or a trial that raised: the legs start -> item -> target
        legs = [layout.start[:2]]
        for name in order:
            if name in spots:
                legs += [spots[name], targets[name]]
        if len(legs) > 1:
            ax.plot(*zip(*legs, strict=True), color=colour, linewidth=1.4, linestyle="--",
                    zorder=5)
    for name, k in fetch_labels(row):
        if name not in spots:
            continue
        x, y = spots[name]
        badge = ax.annotate(str(k), (x, y), xytext=(-10, 8), textcoords="offset points",
                            fontsize=8, fontweight="bold", color="white", ha="center",
                            va="center", zorder=12,
                            bbox={"boxstyle": "circle,pad=0.25", "facecolor": colour,
                                  "edgecolor": "white", "linewidth": 0.6})
        movable(badge, badge_candidates())
    for x, y in failed_spots(layout, row):
        ax.plot(x, y, marker="x", color=FAILED, markersize=11, markeredgewidth=2.5, zorder=11)


def _path_in_sequence(ax: Any, xy: Sequence[Sequence[float]], colour: str) -> None:
    """The bold path, light where it starts and full colour where it ends (by the length
    driven), so overlapping legs can be told apart in the order they were driven."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgb

    points = np.asarray(xy, dtype=float)
    segments = np.stack([points[:-1], points[1:]], axis=1)
    lengths = np.linalg.norm(points[1:] - points[:-1], axis=1)
    done = (np.cumsum(lengths) - lengths / 2) / max(float(lengths.sum()), 1e-9)
    base = np.asarray(to_rgb(colour))
    shade = 0.3 + 0.7 * done[:, None]  # (30 % of the colour at the start, all at the end)
    colours = (1 - shade) * 1.0 + shade * base
    ax.add_collection(LineCollection(segments, colors=colours, linewidths=2.2, zorder=5,
                                     capstyle="round"))


def failed_spots(layout: Layout, row: dict[str, Any]) -> list[tuple[float, float]]:
    """Where a failed trial went wrong: the start spot of each item (or the middle of each
    drawer or cupboard) a failure names; for a trial that raised, where it stopped."""
    if ok(row):
        return []
    spots = {s.name: (s.x, s.y) for s in layout.items}
    spots.update({b.name: ((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2) for b in layout.containers})
    named = [spots[f["item"]] for f in row.get("failures") or []
             if isinstance(f, dict) and f.get("item") in spots]
    path = row.get("driven_path") or []
    return sorted(set(named)) or ([tuple(path[-1])] if path else [])


def _arrows(ax: Any, xy: Sequence[Sequence[float]], colour: str) -> None:
    """Small arrowheads along a path (every ~1.2 m) to show the direction of travel."""
    travelled, next_at = 0.0, 0.6
    for (x0, y0), (x1, y1) in zip(xy, xy[1:], strict=False):
        length = math.hypot(x1 - x0, y1 - y0)
        while length > 0 and travelled + length >= next_at:
            s = (next_at - travelled) / length
            x, y = x0 + s * (x1 - x0), y0 + s * (y1 - y0)
            dx, dy = (x1 - x0) / length * 0.01, (y1 - y0) / length * 0.01
            ax.annotate("", (x + dx, y + dy), xytext=(x, y), zorder=6,
                        arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 0,
                                    "mutation_scale": 11})
            next_at += 1.2
        travelled += length


def _runs_alongside(bar: Any, items: Sequence[Any]) -> bool:
    """Does a longer bar of the same depth overlap this one in time (a parallel step)?"""
    span = bar.end - bar.start
    for other in items:
        if other is bar or other.depth != bar.depth:
            continue
        overlap = min(bar.end, other.end) - max(bar.start, other.start)
        if overlap > 1e-6 and (other.end - other.start, other.start) > (span, bar.start):
            return True
    return False


def _wrap(text: str, width: int) -> str:
    words, lines, line = text.split(" "), [], ""
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return "\n".join(lines + [line])


def timeline(row: dict[str, Any], path: Path) -> Path:
    """The trial's task tree as bars over robot time, one lane per depth; failed actions
    outlined red, instant failed attempts as red crosses (with their count); a step run
    at the same time as a longer one (in parallel) as a strip along the lane's top."""
    return _save(timeline_figure(row), path)


def timeline_figure(row: dict[str, Any]) -> Any:
    """The figure `timeline` saves."""
    from matplotlib.patches import Patch

    plt = pyplot()
    items = bars(row.get("actions") or [])
    depths = sorted({b.depth for b in items}) or [0]
    end = max((b.end for b in items), default=1.0) or 1.0
    fig, ax = plt.subplots(figsize=(11, 1.15 + 0.62 * len(depths)))
    ax.set_xlim(0, end * 1.01)
    ax.set_ylim(len(depths) - 0.4, -0.6)
    names = ("actions", "their steps", "inside those")
    ax.set_yticks(range(len(depths)), [names[min(d, 2)] for d in depths], fontsize=7)
    chars_per_s = 11 * DPI * 0.85 / end / 5.2  # rough: characters that fit in 1 s of bar
    crosses: dict[tuple[int, float], list[Bar]] = {}
    for bar in items:
        lane = depths.index(bar.depth)
        width = bar.end - bar.start
        colour = ACTION_COLOURS.get(bar.name, ACTION_OTHER)
        if width <= 1e-6:
            if bar.failed:
                crosses.setdefault((lane, round(bar.start, 2)), []).append(bar)
            continue
        if _runs_alongside(bar, items):  # (a motion at the same time as a longer one, in
            # parallel: a strip along the lane's top, so neither hides the other's name)
            ax.barh(lane - 0.3, width, left=bar.start, height=0.16, color=colour,
                    edgecolor=FAILED if bar.failed else colour, linewidth=0.5, zorder=4)
            continue
        ax.barh(lane, width, left=bar.start, height=0.7 if bar.depth == 0 else 0.55,
                color=colour, edgecolor=FAILED if bar.failed else "white",
                linewidth=2.0 if bar.failed else 0.5, hatch="//" if bar.failed else None)
        fits = [_short(bar.name) + (f" {bar.object}" if bar.object else ""),
                bar.object or "", _short(bar.name)]
        label = next((t for t in fits if t and len(t) <= width * chars_per_s), "")
        if label:
            ax.text(bar.start + width / 2, lane, label, ha="center", va="center",
                    fontsize=6.5, color="black" if bar.name in ("TransportAction",
                                                                 "MoveTorsoAction",
                                                                 "ParkArmsAction")
                    else "white", clip_on=True)
    for (lane, t), group in sorted(crosses.items()):
        ax.plot([t], [lane], marker="x", color=FAILED, markersize=8, markeredgewidth=2,
                zorder=5)
        if len(group) > 1:
            ax.text(t, lane - 0.33, f"{len(group)}x", color=FAILED, fontsize=6.5,
                    ha="center", va="bottom")
    status = "succeeded" if ok(row) else "FAILED"
    ax.set_title(f"{row['setup']} / {row['strategy']} / trial {row['trial']}: {status}; "
                 f"robot time {end:.1f} s of driving and arm motion", fontsize=9,
                 color="black" if ok(row) else FAILED)
    ax.set_xlabel("robot time (s): driving + arm motion (planning not counted)", fontsize=8)
    ax.tick_params(axis="x", labelsize=7)
    ax.grid(axis="x", color="#eeeeee", zorder=0)
    ax.set_axisbelow(True)
    used = sorted({b.name for b in items}, key=lambda n: list(ACTION_COLOURS).index(n)
                  if n in ACTION_COLOURS else 99)
    handles = [Patch(facecolor=ACTION_COLOURS.get(n, ACTION_OTHER), label=_short(n))
               for n in used]
    if any(b.failed for b in items):
        handles.append(Patch(facecolor="white", edgecolor=FAILED, hatch="//", linewidth=2,
                             label="failed"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7,
              frameon=False)
    fig.tight_layout()
    return fig


def _short(name: str) -> str:
    return name.removesuffix("Action")
