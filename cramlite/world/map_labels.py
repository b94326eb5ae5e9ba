"""Label placement on a top-down map, once the figure's layout is known: each movable
label (a furniture or container name, a fetch-order badge) is tried at a few candidate
places and put at the first where it covers no other text, no item or target marker and
no leader line (measured as matplotlib draws them, in pixels).

A small greedy routine, written here rather than taken from `adjustText`: the candidates
are few and known (along a box, beside it; around an item), which adjustText's
force-directed nudging does not know, and it would be a new dependency for the plots
extra.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

#: Marks a movable text: the attribute holds its candidates (see `furniture_candidates`
#: and `badge_candidates`).
CANDIDATES = "_cramlite_candidates"
#: The gid of leader lines (label to spot), obstacles for the labels placed.
LEADER = "leader"
#: Pixels kept free around a marker.
MARKER_PAD_PX = 4.0


def movable(text: Any, candidates: Sequence[dict[str, Any]]) -> Any:
    """Mark `text` as placed by `settle_labels`, at the first free one of `candidates`
    (each: keyword arguments for the text: position or offset, alignment, rotation)."""
    setattr(text, CANDIDATES, list(candidates))
    return text


def furniture_candidates(x0: float, y0: float, x1: float, y1: float, gap: float = 0.04,
                         ) -> list[dict[str, Any]]:
    """Places for a box's name: inside along its long side (middle first), then beside
    it (left, right, below, above)."""
    middle = ((x0 + x1) / 2, (y0 + y1) / 2)
    tall = (y1 - y0) > 1.5 * (x1 - x0)
    inside = []
    for f in (0.5, 0.32, 0.68, 0.18, 0.82):
        xy = (middle[0], y0 + f * (y1 - y0)) if tall else (x0 + f * (x1 - x0), middle[1])
        inside.append({"xy": xy, "ha": "center", "va": "center", "rotation": 90 if tall else 0})
    beside = [{"xy": (x0 - gap, middle[1]), "ha": "right", "va": "center", "rotation": 0},
              {"xy": (x1 + gap, middle[1]), "ha": "left", "va": "center", "rotation": 0},
              {"xy": (middle[0], y0 - gap), "ha": "center", "va": "top", "rotation": 0},
              {"xy": (middle[0], y1 + gap), "ha": "center", "va": "bottom", "rotation": 0},
              {"xy": (x0 - gap, y0 + 0.2 * (y1 - y0)), "ha": "right", "va": "center",
               "rotation": 0},
              {"xy": (x0 - gap, y0 + 0.8 * (y1 - y0)), "ha": "right", "va": "center",
               "rotation": 0}]
    return inside + beside


def badge_candidates() -> list[dict[str, Any]]:
    """Offsets (points) of a badge from its item: up-left first, then around it."""
    out = []
    for radius in (12, 19, 27):
        for dx, dy in ((-0.8, 0.65), (0.8, 0.65), (-0.8, -0.65), (0.8, -0.65), (0, 1),
                       (0, -1), (-1, 0), (1, 0)):
            out.append({"offset": (dx * radius, dy * radius)})
    return out


def settle_labels(fig: Any) -> None:
    """Place every movable text of the figure's axes (in drawing order). (The figure is
    laid out without rendering its pixels: the text's extents need the layout only; the
    saved pictures are the same, 0.1 s less a map.)"""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        texts = [t for t in ax.texts if t.get_visible() and t.get_text().strip()]
        placed = [_extent(t, renderer) for t in texts if not hasattr(t, CANDIDATES)]
        leaders = list(_leader_segments(ax))
        markers = _markers(ax)
        for text in (t for t in texts if hasattr(t, CANDIDATES)):
            own = np.asarray(ax.transData.transform(text.xy)) if hasattr(text, "xyann") \
                else None
            best, fewest = None, None
            for candidate in getattr(text, CANDIDATES):
                _apply(text, candidate)
                box = _extent(text, renderer)
                conflicts = _conflicts(box, placed, leaders, markers, own)
                if fewest is None or conflicts < fewest:
                    best, fewest = candidate, conflicts
                if conflicts == 0:
                    break
            _apply(text, best)
            placed.append(_extent(text, renderer))


def _apply(text: Any, candidate: dict[str, Any]) -> None:
    if "offset" in candidate:
        text.xyann = candidate["offset"]
        return
    text.set_position(candidate["xy"])
    text.set_ha(candidate["ha"])
    text.set_va(candidate["va"])
    text.set_rotation(candidate["rotation"])


def _extent(text: Any, renderer: Any) -> Any:
    box = text.get_window_extent(renderer)
    patch = text.get_bbox_patch()
    if patch is not None:
        text.update_bbox_position_size(renderer)  # (where the text is now)
        box = type(box).union([box, patch.get_window_extent(renderer)])
    return box


def _leader_segments(ax: Any) -> Iterable[tuple[np.ndarray, np.ndarray]]:
    for line in ax.lines:
        if line.get_gid() == LEADER and len(line.get_xdata()) >= 2:
            xy = ax.transData.transform(np.column_stack(line.get_data()))
            yield from zip(xy[:-1], xy[1:], strict=True)


def _markers(ax: Any) -> np.ndarray:
    points = [np.column_stack(line.get_data()) for line in ax.lines
              if line.get_marker() not in (None, "None", "", " ") and len(line.get_xdata()) == 1]
    if not points:
        return np.zeros((0, 2))
    return ax.transData.transform(np.vstack(points).astype(float))


def _conflicts(box: Any, placed: list[Any], leaders: list, markers: np.ndarray,
               own: np.ndarray | None) -> int:
    count = sum(1 for other in placed if _overlap(box, other))
    count += sum(1 for a, b in leaders if length_inside(box, a, b) > 1.0)
    for x, y in markers:
        if own is not None and abs(x - own[0]) < 1 and abs(y - own[1]) < 1:
            continue  # (a badge beside its own item)
        if box.x0 - MARKER_PAD_PX < x < box.x1 + MARKER_PAD_PX and \
                box.y0 - MARKER_PAD_PX < y < box.y1 + MARKER_PAD_PX:
            count += 1
    return count


def length_inside(box: Any, a: np.ndarray, b: np.ndarray) -> float:
    """How much of the segment a-b (pixels) runs inside `box` (Liang-Barsky clipping)."""
    d = b - a
    low, high = 0.0, 1.0
    for p, q in ((-d[0], a[0] - box.x0), (d[0], box.x1 - a[0]), (-d[1], a[1] - box.y0),
                 (d[1], box.y1 - a[1])):
        if abs(p) < 1e-12:
            if q < 0:
                return 0.0
            continue
        t = q / p
        if p < 0:
            low = max(low, t)
        else:
            high = min(high, t)
        if low > high:
            return 0.0
    return float(np.hypot(*d)) * (high - low)


def _overlap(a: Any, b: Any) -> bool:
    return min(a.x1, b.x1) - max(a.x0, b.x0) > 0.5 and min(a.y1, b.y1) - max(a.y0, b.y0) > 0.5


__all__ = ["LEADER", "badge_candidates", "furniture_candidates", "length_inside", "movable",
           "settle_labels"]
