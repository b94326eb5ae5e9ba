"""A top-down map of a setup: the kitchen seen from above (matplotlib, no rendering).

`load_layout` reads the fixed geometry once from the setup's planning scene (the
furniture's boxes with the drawers and doors closed, the containers) and the setup (the
robot's start, each item's start spot and target); `draw_layout` draws it on a matplotlib
axes with every item and target labelled in two columns beside the kitchen (leader lines
to the spots), so labels never cover each other or the floor the robot drives on.
`save_top_view` is `cramlite show SETUP --top`. Needs matplotlib (`pip install
cramlite[plots]`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cramlite.world.setup import Setup

#: Links drawn as walls (dark, unlabelled) and the floor (the background).
WALL_PREFIX = "wall"
FLOOR = "floor"
#: Width (m) of the label columns left and right of the kitchen, and the label spacing.
LABEL_COLUMN_M = 1.6
LABEL_GAP_M = 0.25
ITEM_COLOUR = "#222222"
TARGET_COLOUR = "#555555"


@dataclass(frozen=True)
class Box:
    name: str
    x0: float
    y0: float
    x1: float
    y1: float
    top: float


@dataclass(frozen=True)
class Spot:
    name: str  #: the item's name
    x: float
    y: float
    container: str | None = None


@dataclass(frozen=True)
class Layout:
    """Everything a top-down map shows, in world metres."""

    setup: str
    boxes: tuple[Box, ...]  #: furniture and walls (not the floor), lowest top first
    containers: tuple[Box, ...]  #: drawers and cupboards (closed), by name
    floor: Box
    start: tuple[float, float, float]  #: robot start x, y, yaw
    items: tuple[Spot, ...]  #: start spots
    targets: tuple[Spot, ...]

    @property
    def label_bounds(self) -> tuple[float, float, float, float]:
        """x0, y0, x1, y1 of the map with its label columns."""
        xs = [self.floor.x0, self.floor.x1] + [b.x0 for b in self.boxes] + \
            [b.x1 for b in self.boxes]
        ys = [self.floor.y0, self.floor.y1] + [b.y0 for b in self.boxes] + \
            [b.y1 for b in self.boxes]
        return (min(xs) - LABEL_COLUMN_M, min(ys) - 0.15, max(xs) + LABEL_COLUMN_M,
                max(ys) + 0.15)


def load_layout(setup: Setup) -> Layout:
    """The setup's map (from its planning scene's models: no simulator)."""
    from cramlite.scene.scene import PlanningScene

    scene = PlanningScene(setup)
    raw = {name: (lo, hi) for name, lo, hi, _ in scene.environment_footprints()}
    moving = {c.link for c in scene.containers.values()}
    containers = []
    for container in sorted(scene.containers.values(), key=lambda c: c.name):
        # a drawer: its moving box; a cupboard: the body its door closes
        lo, hi = raw.get(container.inside_link) or raw[container.link]
        containers.append(Box(container.name, lo[0], lo[1], hi[0], hi[1], hi[2]))
    boxes = [Box(name, lo[0], lo[1], hi[0], hi[1], hi[2]) for name, (lo, hi) in raw.items()
             if name != FLOOR and name not in moving]
    floor = next((Box(FLOOR, lo[0], lo[1], hi[0], hi[1], hi[2])
                  for name, (lo, hi) in raw.items() if name == FLOOR), None)
    if floor is None:
        xs = [b.x0 for b in boxes] + [b.x1 for b in boxes]
        ys = [b.y0 for b in boxes] + [b.y1 for b in boxes]
        floor = Box(FLOOR, min(xs), min(ys), max(xs), max(ys), 0.0)
    start = setup.robot_start
    return Layout(
        setup=setup.name,
        boxes=tuple(sorted(boxes, key=lambda b: (b.top, b.name))),
        containers=tuple(containers), floor=floor, start=(start.x, start.y, start.yaw),
        items=tuple(Spot(i.name, i.pose.x, i.pose.y, i.container) for i in setup.items),
        targets=tuple(Spot(i.name, i.target.x, i.target.y) for i in setup.items))


def _labelled(name: str, names: set[str]) -> bool:
    """Label a piece of furniture, not its parts (`counter_base` is part of `counter`)."""
    if name.startswith(WALL_PREFIX):
        return False
    parts = name.split("_")
    return not any("_".join(parts[:k]) in names for k in range(1, len(parts)))


def spread(values: list[float], gap: float, low: float, high: float) -> list[float]:
    """Positions near `values` (in the same order) at least `gap` apart, within
    [low, high] where there is room."""
    order = sorted(range(len(values)), key=lambda i: values[i])
    placed = [values[i] for i in order]
    for k in range(1, len(placed)):
        placed[k] = max(placed[k], placed[k - 1] + gap)
    overflow = placed[-1] - high if placed else 0.0
    if overflow > 0:
        placed[-1] -= overflow
        for k in range(len(placed) - 2, -1, -1):
            placed[k] = min(placed[k], placed[k + 1] - gap)
    placed = [max(p, low + gap * k) if p < low else p for k, p in enumerate(placed)]
    out = [0.0] * len(values)
    for k, i in enumerate(order):
        out[i] = placed[k]
    return out


def draw_layout(ax: Any, layout: Layout, legend: bool = True, font_size: float = 7.0) -> None:
    """The kitchen, the robot's start, the items' start spots and targets, labelled."""
    from matplotlib.patches import FancyArrow, Rectangle

    f = _inside_walls(layout)
    ax.add_patch(Rectangle((f.x0, f.y0), f.x1 - f.x0, f.y1 - f.y0, facecolor="#fbfaf7",
                           edgecolor="none", zorder=0))
    names = {b.name for b in layout.boxes}
    for box in layout.boxes:
        wall = box.name.startswith(WALL_PREFIX)
        shade = "#6b6b6b" if wall else _grey(box.top)
        ax.add_patch(Rectangle((box.x0, box.y0), box.x1 - box.x0, box.y1 - box.y0,
                               facecolor=shade, edgecolor="#8a8a8a" if not wall else "none",
                               linewidth=0.5, zorder=1))
    _metre_grid(ax, f, font_size)
    for box in layout.boxes:
        if _labelled(box.name, names) and (box.x1 - box.x0) * (box.y1 - box.y0) > 0.05:
            _box_name(ax, box, font_size, "#3a3a3a")
    for box in layout.containers:
        ax.add_patch(Rectangle((box.x0, box.y0), box.x1 - box.x0, box.y1 - box.y0,
                               facecolor="none", edgecolor="#7a4e9c", linestyle="--",
                               linewidth=0.9, zorder=2))
        if box.name not in names:
            _box_name(ax, box, font_size - 1.0, "#7a4e9c")
    x, y, yaw = layout.start
    ax.add_patch(FancyArrow(x, y, 0.35 * math.cos(yaw), 0.35 * math.sin(yaw), width=0.05,
                            head_width=0.2, head_length=0.15, color="black", zorder=6))
    ax.plot([x], [y], marker="o", markersize=9, markerfacecolor="white",
            markeredgecolor="black", zorder=7)
    ax.text(x, y - 0.22, "robot start", ha="center", va="top", fontsize=font_size,
            zorder=7, bbox={"boxstyle": "round,pad=0.15", "facecolor": "white",
                            "edgecolor": "none", "alpha": 0.8})
    _spots_with_labels(ax, layout, font_size)
    x0, y0, x1, y1 = layout.label_bounds
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    for spine in ax.spines.values():
        spine.set_visible(False)
    if legend:
        ax.legend(handles=legend_handles(), loc="lower left", fontsize=font_size - 0.5,
                  framealpha=0.9)


def _box_name(ax: Any, box: Box, font_size: float, colour: str) -> None:
    """A box's name, placed later (`map_labels.settle_labels`) where no marker, text or
    leader line is: inside along its long side, or else beside it."""
    from cramlite.world.map_labels import furniture_candidates, movable

    candidates = furniture_candidates(box.x0, box.y0, box.x1, box.y1)
    first = candidates[0]
    text = ax.text(*first["xy"], box.name, ha=first["ha"], va=first["va"],
                   rotation=first["rotation"], fontsize=font_size, color=colour, zorder=8,
                   bbox={"boxstyle": "square,pad=0.1", "facecolor": "white", "alpha": 0.55,
                         "edgecolor": "none"})
    movable(text, candidates)


def _metre_grid(ax: Any, floor: Box, font_size: float) -> None:
    """Faint lines every metre over the floor, with metre ticks on the axes: a user
    writing a setup reads coordinates off the map."""
    xs = [float(v) for v in range(math.ceil(floor.x0), math.floor(floor.x1) + 1)]
    ys = [float(v) for v in range(math.ceil(floor.y0), math.floor(floor.y1) + 1)]
    for x in xs:
        ax.plot([x, x], [floor.y0, floor.y1], color="#d8d4cc", linewidth=0.4, zorder=0.5)
    for y in ys:
        ax.plot([floor.x0, floor.x1], [y, y], color="#d8d4cc", linewidth=0.4, zorder=0.5)
    ax.set_xticks(xs, [f"{v:g}" for v in xs], fontsize=font_size - 1)
    ax.set_yticks(ys, [f"{v:g}" for v in ys], fontsize=font_size - 1)
    ax.tick_params(length=2, pad=1, colors="#666666")
    ax.set_xlabel("x (m)", fontsize=font_size - 0.5, color="#666666", labelpad=1)
    ax.set_ylabel("y (m)", fontsize=font_size - 0.5, color="#666666", labelpad=1)


def _inside_walls(layout: Layout) -> Box:
    """The floor, clipped to the walls' outline (a floor may reach under a wall)."""
    f = layout.floor
    walls = [b for b in layout.boxes if b.name.startswith(WALL_PREFIX)]
    if not walls:
        return f
    return Box(f.name, max(f.x0, min(b.x0 for b in walls)), max(f.y0, min(b.y0 for b in walls)),
               min(f.x1, max(b.x1 for b in walls)), min(f.y1, max(b.y1 for b in walls)), f.top)


def legend_handles() -> list[Any]:
    from matplotlib.lines import Line2D

    return [Line2D([], [], marker="o", linestyle="none", color=ITEM_COLOUR, markersize=6,
                   label="item, where it starts"),
            Line2D([], [], marker="s", linestyle="none", markerfacecolor="white",
                   markeredgecolor=TARGET_COLOUR, markersize=6, label="target (where it goes)"),
            Line2D([], [], marker=r"$\rightarrow$", linestyle="none", color="black",
                   markersize=9, label="robot start and heading"),
            Line2D([], [], color="#7a4e9c", linestyle="--", label="drawer / cupboard")]


def _spots_with_labels(ax: Any, layout: Layout, font_size: float) -> None:
    """Markers at the spots; labels in a column left or right of the kitchen (the side
    nearer to the spot), spread apart, with leader lines."""
    f = layout.floor
    middle = (f.x0 + f.x1) / 2
    x0, y0, x1, y1 = layout.label_bounds
    entries = [(s, "item") for s in layout.items] + [(s, "target") for s in layout.targets]
    for side in ("left", "right"):
        group = [(s, kind) for s, kind in entries if (s.x < middle) == (side == "left")]
        if not group:
            continue
        ys = spread([s.y for s, _ in group], LABEL_GAP_M, y0 + 0.1, y1 - 0.1)
        edge = min(b.x0 for b in layout.boxes) if side == "left" else \
            max(b.x1 for b in layout.boxes)
        # labels end toward the kitchen, where their leader line starts (a line drawn
        # from the column's outer side ran under the labels' text)
        column = edge - 0.12 if side == "left" else edge + 0.12
        for (spot, kind), label_y in zip(group, ys, strict=True):
            item = kind == "item"
            text = spot.name if item else f"target: {spot.name}"
            if item and spot.container:
                text += f" (in {spot.container})"
            ax.plot([spot.x, edge, column + (0.04 if side == "left" else -0.04)],
                    [spot.y, label_y, label_y], color="#b0b0b0", linewidth=0.5, zorder=3,
                    gid="leader")
            ax.text(column, label_y, text, ha="right" if side == "left" else "left",
                    va="center", fontsize=font_size, zorder=8,
                    color=ITEM_COLOUR if item else TARGET_COLOUR,
                    fontweight="bold" if item else "normal",
                    fontstyle="normal" if item else "italic")
    for spot in layout.items:
        ax.plot([spot.x], [spot.y], marker="o", markersize=5.5, color=ITEM_COLOUR,
                markeredgecolor="white", markeredgewidth=0.6, zorder=9)
    for spot in layout.targets:
        ax.plot([spot.x], [spot.y], marker="s", markersize=5.5, markerfacecolor="white",
                markeredgecolor=TARGET_COLOUR, markeredgewidth=1.0, zorder=9)


def _grey(top: float) -> str:
    """Higher furniture is darker."""
    level = int(max(150, min(225, 225 - 35 * top)))
    return f"#{level:02x}{level:02x}{level:02x}"


def save_top_view(setup: Setup, path: str | Path, width_px: int = 1024,
                  height_px: int = 768) -> Path:
    """Draw the setup's top-down map into an image file (`cramlite show --top`)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = top_view_figure(setup, width_px, height_px)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=fig.dpi)
    plt.close(fig)
    return path


def top_view_figure(setup: Setup, width_px: int = 1024, height_px: int = 768) -> Any:
    """The figure `save_top_view` saves."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    layout = load_layout(setup)
    dpi = 100
    fig, ax = plt.subplots(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
    draw_layout(ax, layout, font_size=max(5.0, min(10.0, 7.0 * height_px / 768)))
    ax.set_title(f"{setup.name}: {setup.description}" if setup.description else setup.name,
                 fontsize=9)
    with warnings.catch_warnings():  # (a picture a few pixels wide has no room for its
        warnings.simplefilter("ignore")  # margins: matplotlib warns, the picture is drawn)
        fig.tight_layout()
    from cramlite.world.map_labels import settle_labels

    settle_labels(fig)
    return fig
