"""Maps a person can read (#27): on every shipped setup's top view and report map, no two
texts overlap (their extents as matplotlib draws them, a badge's circle included), no
leader line runs through a label, no item or target marker sits on a furniture or
container name, and the axes show metres."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from cramlite.world.map_labels import length_inside
from cramlite.world.setup import load_setup

SETUPS = ["v1", "v2", "v3", "v4", "v5", "c1", "c2", "c3"]


def _texts(fig) -> list:
    """Every visible, non-empty text of the figure's axes (titles and legend apart: they
    sit outside the kitchen)."""
    out = []
    for ax in fig.axes:
        for text in ax.texts:
            if text.get_visible() and text.get_text().strip():
                out.append(text)
    return out


def _box(text, renderer):
    patch = text.get_bbox_patch()
    box = text.get_window_extent(renderer)
    if patch is not None:
        box = type(box).union([box, patch.get_window_extent(renderer)])
    return box


def _overlaps(fig) -> list[tuple[str, str]]:
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_text(), _box(t, renderer)) for t in _texts(fig)]
    return [(a, b) for (a, p), (b, q) in itertools.combinations(boxes, 2)
            if p.overlaps(q) and p.intersection(p, q).width > 0.5
            and p.intersection(p, q).height > 0.5]


def _lines_through_labels(fig) -> list[str]:
    """Labels a thin grey leader line passes through (more than its end touching)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    found = []
    for ax in fig.axes:
        leaders = [line for line in ax.lines if line.get_gid() == "leader"]
        for text in ax.texts:
            if not text.get_text().strip():
                continue
            box = text.get_window_extent(renderer).expanded(0.95, 0.7)
            for line in leaders:
                xy = ax.transData.transform(np.column_stack(line.get_data()))
                for a, b in itertools.pairwise(xy):
                    if length_inside(box, a, b) > 2.0:
                        found.append(text.get_text())
    return sorted(set(found))


def _markers_on_names(fig, layout) -> list[str]:
    """Furniture and container names with an item or target marker on them."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    furniture = {b.name for b in layout.boxes} | {b.name for b in layout.containers}
    points = [(s.x, s.y) for s in (*layout.items, *layout.targets)]
    found = []
    for ax in fig.axes:
        pixels = ax.transData.transform(np.array(points))
        for text in ax.texts:
            if text.get_text() not in furniture:
                continue
            box = text.get_window_extent(renderer).expanded(1.0, 1.0).padded(4)
            if any(box.contains(x, y) for x, y in pixels):
                found.append(text.get_text())
    return found


@pytest.mark.parametrize("name", SETUPS)
def test_the_top_view_has_no_overlapping_text_and_metre_axes(name: str) -> None:
    import matplotlib.pyplot as plt

    from cramlite.world.topdown import load_layout, top_view_figure

    setup = load_setup(name)
    fig = top_view_figure(setup)
    try:
        assert _overlaps(fig) == []
        assert _lines_through_labels(fig) == []
        assert _markers_on_names(fig, load_layout(setup)) == []
        ax = fig.axes[0]
        ticks = [t for t in ax.get_xticks() if t == round(t)]
        assert len(ticks) >= 3 and "x (m)" in ax.get_xlabel()
    finally:
        plt.close(fig)


@pytest.mark.parametrize("name", ["v1", "c1", "c3"])
def test_the_report_map_has_no_overlapping_text(name: str) -> None:
    import matplotlib.pyplot as plt

    from cramlite.report.figures import MAP_DPI, setup_map_figure
    from cramlite.world.topdown import load_layout

    setup = load_setup(name)
    layout = load_layout(setup)
    names = [s.name for s in setup.items]
    rows = []
    for strategy, order in (("opm", names), ("baseline", names[::-1])):
        path = [list(layout.start[:2])]
        for item in order:
            spot = next(s for s in layout.items if s.name == item)
            target = next(s for s in layout.targets if s.name == item)
            path += [[spot.x - 0.6, spot.y], [target.x + 0.6, target.y]]
        rows.append({"strategy": strategy, "trial": "0", "success": "True",
                     "order": " ".join(order), "driven_path": path, "failures": []})
    fig = setup_map_figure(layout, rows, ["opm", "baseline"],
                           {"opm": "#1f77b4", "baseline": "#ff7f0e"},
                           {r["strategy"]: r for r in rows})
    fig.set_dpi(MAP_DPI)
    try:
        assert _overlaps(fig) == []
        assert _lines_through_labels(fig) == []
        assert _markers_on_names(fig, layout) == []
    finally:
        plt.close(fig)


def test_a_timeline_with_a_parallel_step_has_no_overlapping_text() -> None:
    """(The torso rising while the base drives drew 'MoveTorso' under 'Transport
    breakfast-cereal' in the report's first timeline.)"""
    import matplotlib.pyplot as plt

    from cramlite.report.figures import timeline_figure

    def node(name, start, end, obj=None, children=()):
        return {"name": name, "object": obj, "start_s": start, "end_s": end,
                "status": "succeeded", "children": list(children), "failure": None}

    actions = [node("ParkArmsAction", 0.0, 2.0),
               node("MoveTorsoAction", 2.0, 21.0),
               node("TransportAction", 2.1, 28.0, "breakfast-cereal",
                    [node("NavigateAction", 2.1, 21.5), node("PickUpAction", 21.5, 25.0,
                                                             "breakfast-cereal")]),
               node("TransportAction", 28.0, 40.0, "cup")]
    fig = timeline_figure({"setup": "v1", "strategy": "baseline", "trial": "0",
                           "success": "True", "actions": actions})
    try:
        assert _overlaps(fig) == []
        labels = [t.get_text() for t in fig.axes[0].texts]
        assert "Transport breakfast-cereal" in labels
    finally:
        plt.close(fig)


def test_the_bold_path_is_coloured_in_the_order_it_was_driven() -> None:
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from cramlite.report.figures import setup_map_figure
    from cramlite.world.topdown import load_layout

    layout = load_layout(load_setup("v1"))
    path = [[-0.5, -1.8], [0.8, -0.5], [0.8, 0.5], [-0.3, 1.2], [0.8, 1.0]]
    row = {"strategy": "opm", "trial": "0", "success": "True", "order": "cup",
           "driven_path": path, "failures": []}
    fig = setup_map_figure(layout, [row], ["opm"], {"opm": "#1f77b4"}, {"opm": row})
    try:
        (bold,) = [c for c in fig.axes[0].collections if isinstance(c, LineCollection)
                   and len(c.get_segments()) == len(path) - 1]
        whiteness = bold.get_colors()[:, :3].sum(axis=1)
        assert np.all(np.diff(whiteness) < 0)  # (lighter first, full colour last)
    finally:
        plt.close(fig)
