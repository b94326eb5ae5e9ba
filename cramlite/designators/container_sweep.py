"""What a drawer or door would push into on its way: checked before a robot pulls or
pushes it (a red-team plan closed a drawer on a breakfast-cereal box 11 cm too long for
it, and the cupboard door through a milk standing at its edge; the robot's own motion
was checked, the container's was not).

Along the container's way, at steps of `SWEEP_STEP`, its moving links and the items
riding in it (a drawer carries what stands inside; a door carries nothing) are checked
against the rest of the kitchen and the items standing still: anything deeper than
`SWEEP_TOLERANCE_M` is a problem, named. Shapes whose bounds stay apart are never
measured (the bounds of all of them at a step: a few array operations), so a sweep with
nothing in its way costs a few milliseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cramlite.designators.context import RobotContext
from cramlite.scene.geometry import depth_text
from cramlite.scene.models import Shape
from cramlite.scene.scene import shape_corners
from cramlite.world.containers import Container

#: The container's way is checked at least this often: 1 cm of a drawer, 2 degrees of a
#: door (at the door's far edge, 45 cm from its hinge, 1.6 cm).
SWEEP_STEP = {"prismatic": 0.01, "revolute": math.radians(2.0)}
#: Contact this shallow is resting contact, not pushing (an item on a drawer's bottom
#: next to its side).
SWEEP_TOLERANCE_M = 0.003


@dataclass
class _Shapes:
    """Shapes (with what each belongs to) and their local corners, placed as asked."""

    owners: list[str]
    shapes: list[Shape]
    local: list[np.ndarray]  #: each shape's corners (a mesh's vertices) in its frame

    @classmethod
    def of(cls, pairs: list[tuple[str, Shape]]) -> _Shapes:
        eye = np.eye(4)
        return cls([o for o, _ in pairs], [s for _, s in pairs],
                   [shape_corners(s, eye) for _, s in pairs])

    def bounds(self, placements: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        if not placements:
            return np.zeros((0, 3)), np.zeros((0, 3))
        points = [c @ p[:3, :3].T + p[:3, 3] for c, p in zip(self.local, placements,
                                                               strict=True)]
        return (np.array([p.min(axis=0) for p in points]),
                np.array([p.max(axis=0) for p in points]))


def sweep_problem(ctx: RobotContext, container: Container, start: float, end: float,
                  ) -> str | None:
    """What moving `container` from `start` to `end` would push into (one line naming
    the two and how deep), or None if its way is clear. Kept per scene by everything it
    depends on (where every drawer, door and item is, what is held): the next trial of a
    setup asks the same."""
    scene = ctx.scene
    key = ("sweep", container.name, float(start), float(end),
           tuple(sorted(scene.belief.world_joints.items())),
           tuple(sorted((name, tuple(np.round(scene.item_matrix(name)[:3], 9).ravel()))
                        for name in scene.items)),
           tuple(sorted(scene.belief.held)))
    if key not in scene.cache:
        scene.cache[key] = _sweep_problem(ctx, container, start, end)
    return scene.cache[key]


def _sweep_problem(ctx: RobotContext, container: Container, start: float, end: float,
                   ) -> str | None:
    scene, collisions = ctx.scene, ctx.collisions
    joint = container.joint
    kind = scene.kitchen.joints[joint].kind
    moved = scene.links_moved_by(joint)
    riding = scene.riding_along(joint)
    held = set(scene.belief.held)
    standing = [n for n in scene.items if n not in riding and n not in held]
    frames = scene.kitchen_frames()
    static_pairs = [(s.link, s) for s in scene.kitchen.shapes if s.link not in moved]
    static = _Shapes.of(static_pairs)
    static_at = [frames[s.link] @ s.in_link for _, s in static_pairs]
    still_pairs = [(name, s) for name in standing for s in scene.items[name].model.shapes]
    still = _Shapes.of(still_pairs)
    still_at = [scene.item_matrix(name) @ s.in_link for name, s in still_pairs]
    moving = _Shapes.of([(s.link, s) for s in scene.kitchen.shapes if s.link in moved])
    carried = _Shapes.of([(name, s) for name in riding
                          for s in scene.items[name].model.shapes])
    fixed = [(static, static_at, *static.bounds(static_at), "kitchen"),
             (still, still_at, *still.bounds(still_at), "item")]
    steps = max(1, math.ceil(abs(end - start) / SWEEP_STEP.get(kind, 0.01)))
    verb = "closing" if abs(end) < abs(start) else "opening"
    # (what rides keeps its place in the container's link: placed from the link's frame)
    in_link = {name: np.linalg.inv(frames[container.link]) @ scene.item_matrix(name)
               for name in riding}
    for value in np.linspace(start, end, steps + 1)[1:]:
        frames = scene.kitchen_frames({joint: float(value)})
        moving_at = [frames[link] @ s.in_link
                     for link, s in zip(moving.owners, moving.shapes, strict=True)]
        carrier = frames[container.link]
        carried_at = [carrier @ in_link[name] @ s.in_link
                      for name, s in zip(carried.owners, carried.shapes, strict=True)]
        for group, placed, what in ((moving, moving_at, "link"), (carried, carried_at, "rider")):
            lo, hi = group.bounds(placed)
            for other, other_at, other_lo, other_hi, other_kind in fixed:
                if what == "link" and other_kind == "kitchen":
                    continue  # (a drawer in its own counter: the kitchen's own business)
                meet = np.argwhere(np.all((lo[:, None] < other_hi[None] - SWEEP_TOLERANCE_M)
                                          & (other_lo[None] < hi[:, None] - SWEEP_TOLERANCE_M),
                                          axis=2))
                for i, j in meet.tolist():
                    depth = collisions.depth(group.shapes[i], placed[i], other.shapes[j],
                                             other_at[j])
                    if depth > SWEEP_TOLERANCE_M:
                        return _problem(verb, container.name, what, group.owners[i],
                                        other_kind, other.owners[j], depth)
    return None


def _problem(verb: str, container: str, what: str, owner: str, other_kind: str,
             other: str, depth: float) -> str:
    into = f"the {other}" if other_kind == "kitchen" else other
    if what == "link":
        return f"{verb} {container} would push its {owner} {depth_text(depth)} into {into}"
    return (f"{verb} {container} would push {owner}, which rides in it, "
            f"{depth_text(depth)} into {into}")
