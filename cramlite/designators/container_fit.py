"""Whether an item fits in the drawer or cupboard it is to be put into: its bounds, turned
as it would stand, inside the container's inside box, and no taller than it.

Checked before a transport into a container moves anything: a cereal box 29 cm tall for a
drawer 18 cm deep used to be carried to the opened drawer and refused there with "could
not put it down at the goal" (or, where it could be put down, left sticking out of a
drawer that then could not close). The bounds are a box's, which a mesh (a spoon) does
not fill: the footprint may stick out by `FOOTPRINT_SLACK_M`, what `replay --check`
tolerates, and the height by `SWEEP_TOLERANCE_M`, as closing it would find (the counter
top is right above a drawer). The checks of record stay the real shapes': the place
pose's, and the container's sweep when it closes: a target the bounds allow may still
be put where the container cannot close (a milk at the cupboard's front edge), and the
container is then left open (see docs/architecture.md).

Only refusing. Preferring, among the place poses, those whose bounds fit was tried and
left out: the bounds are stricter than the sweep (a milk put 1 cm from the cupboard's
front, whose door then closed past it, does not fit by them), and the extra place poses
it asks for draw from the trial's generator, so all that follows changes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from cramlite.designators.container_sweep import SWEEP_TOLERANCE_M
from cramlite.designators.context import RobotContext
from cramlite.designators.failures import PlacementFailed
from cramlite.world.containers import Container, turned_halves

Vec3 = tuple[float, float, float]

#: How far an item's bounds may stick out of the inside for the target to be tried: what
#: `replay --check` tolerates (`penetrations`' default), as a mesh does not fill its box.
FOOTPRINT_SLACK_M = 0.01
#: Any yaw: the bounds of a turned box repeat every half turn; tried every degree.
_ANY_YAW = np.radians(np.arange(180.0))


def fits_at(ctx: RobotContext, name: str, container: Container, local: Vec3,
            item_yaw: float) -> bool:
    """Does item `name`, its bottom centre at `local` (in the inside's frame) and turned
    to `item_yaw` (world), fit inside `container` (its bounds within `FOOTPRINT_SLACK_M`
    of the walls; no taller than the inside, within the sweep's tolerance)?"""
    extents = ctx.scene.items[name].extents
    yaw = 0.0 if _round(ctx, name) else item_yaw - ctx.scene.inside_yaw(container)
    half_x, half_y = turned_halves(extents, yaw)
    return (container.fits(local, half_x, half_y, 0.0, slack=FOOTPRINT_SLACK_M)
            and local[2] + extents[2] <= container.inside_max[2] + SWEEP_TOLERANCE_M)


def check_fits(ctx: RobotContext, name: str, target: Vec3, spots: Sequence[Vec3],
               container: Container, target_yaw: float | None) -> None:
    """PlacementFailed, naming the item's size and the inside's, if the item stands in
    `container` at none of `spots` (the target and the places around it a transport
    tries, as they are with the container closed) at `target_yaw` (or a turn of it by its
    symmetry), or at any yaw where none is asked for."""
    inside = [local for found, local in map(ctx.scene.container_at, spots)
              if found is container]
    model = ctx.scene.items[name].model
    if _round(ctx, name) or target_yaw is None:
        yaws = [0.0] if _round(ctx, name) else _ANY_YAW + ctx.scene.inside_yaw(container)
        how = "at any yaw"
    else:
        period = math.radians(model.yaw_symmetry_deg)
        yaws = [target_yaw + k * period for k in range(max(1, round(2 * math.pi / period)))]
        how = f"turned to yaw {target_yaw:.2f} rad"
    if any(fits_at(ctx, name, container, local, float(yaw))
           for local in inside for yaw in yaws):
        return
    ex, ey, ez = model.extents
    bottom, top = container.inside_min[2], container.inside_max[2]
    if ez > top - bottom + SWEEP_TOLERANCE_M:
        why = f"it is {ez:.2f} m tall and the inside {top - bottom:.2f} m"
    else:
        x, y, z = target
        why = f"at ({x:.2f}, {y:.2f}, {z:.2f}) it would stick out of the inside {how}"
    raise PlacementFailed(f"it ({ex:.2f} x {ey:.2f} x {ez:.2f} m) does not fit in "
                          f"{container.name} ({container.describe_inside()}): {why}, so "
                          f"{container.name} could not be closed over it", obj=name)


def _round(ctx: RobotContext, name: str) -> bool:
    """Looks the same at any turn (a cup, a bowl): its bounds at yaw 0 hold at any."""
    return ctx.scene.items[name].model.yaw_symmetry_deg <= 0
