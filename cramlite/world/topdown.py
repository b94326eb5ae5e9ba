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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cramlite.world.setup import Setup

#: Links drawn as walls (dark, unlabelled) and the floor (the background).
WALL_PREFIX = "wall"
FLOOR = "floor"
#: Width (m) of the label columns left and right of the kitchen, and the label spacing.
LABEL_COLUMN_M = 1.6
LABEL_GAP_M = 0.2
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
    for box in layout.boxes:
        if _labelled(box.name, names) and (box.x1 - box.x0) * (box.y1 - box.y0) > 0.05:
            long_side_y = (box.y1 - box.y0) > 1.5 * (box.x1 - box.x0)
            ax.text((box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2, box.name,
                    ha="center", va="center", fontsize=font_size, color="#3a3a3a",
                    rotation=90 if long_side_y else 0, zorder=2, alpha=0.8)
    for box in layout.containers:
        ax.add_patch(Rectangle((box.x0, box.y0), box.x1 - box.x0, box.y1 - box.y0,
                               facecolor="none", edgecolor="#7a4e9c", linestyle="--",
                               linewidth=0.9, zorder=2))
        if box.name not in names:
            ax.text(box.x0 + 0.03, (box.y0 + box.y1) / 2, box.name, ha="left", va="center",
                    fontsize=font_size - 1.5, color="#7a4e9c", zorder=2, rotation=90)
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
    ax.set_xticks([])
    ax.set_yticks([])
    for spine in ax.spines.values():
        spine.set_visible(False)
    if legend:
        ax.legend(handles=legend_handles(), loc="lower left", fontsize=font_size - 0.5,
                  framealpha=0.9)


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
        column = x0 + 0.08 if side == "left" else x1 - 0.08
        edge = min(b.x0 for b in layout.boxes) if side == "left" else \
            max(b.x1 for b in layout.boxes)
        for (spot, kind), label_y in zip(group, ys, strict=True):
            item = kind == "item"
            text = spot.name if item else f"target: {spot.name}"
            if item and spot.container:
                text += f" (in {spot.container})"
            ax.plot([spot.x, edge, column + (0.05 if side == "left" else -0.05)],
                    [spot.y, label_y, label_y], color="#b0b0b0", linewidth=0.5, zorder=3)
            ax.text(column, label_y, text, ha="left" if side == "left" else "right",
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

    layout = load_layout(setup)
    dpi = 100
    fig, ax = plt.subplots(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
    draw_layout(ax, layout, font_size=max(5.0, min(10.0, 7.0 * height_px / 768)))
    ax.set_title(f"{setup.name}: {setup.description}" if setup.description else setup.name,
                 fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
