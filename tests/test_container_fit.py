"""A transport into a drawer or cupboard the item cannot fit in is refused before
anything moves, naming the item's size and the inside's (a 29 cm cereal box was carried to
the opened 18 cm drawer and refused there with "could not put it down at the goal"); a
target where it fits, at some yaw of the places a transport tries, is not. Kinematic."""

from __future__ import annotations

import math

import pytest

from cramlite import ParkArmsAction, TransportAction, simulated_robot
from cramlite.designators.container_fit import check_fits
from cramlite.designators.failures import PlacementFailed
from cramlite.designators.locations import PlacingLocation
from cramlite.designators.objects import as_object
from cramlite.world.setup import load_setup


def _target(ctx, container: str, x: float, y: float) -> tuple[float, float, float]:
    """A point of a container's inside bottom, as it is with the container closed."""
    inside = ctx.scene.containers[container]
    frame = ctx.scene.kitchen_frames({inside.joint: 0.0})[inside.inside_link]
    point = frame @ [x, y, inside.inside_min[2], 1.0]
    return tuple(float(v) for v in point[:3])


def test_a_box_taller_than_the_drawer_is_refused_before_anything_moves(tmp_path) -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        ParkArmsAction().perform(ctx)
        before = (dict(ctx.scene.world_joint_positions()), ctx.time_s,
                  ctx.scene.object_pose("breakfast-cereal"))
        target = _target(ctx, "drawer_1", 0.18, 0.0)
        with pytest.raises(PlacementFailed,
                           match=r"it \(0.07 x 0.19 x 0.29 m\) does not fit in drawer_1 "
                                 r"\(0.30 x 0.33 m and 0.18 m tall\): it is 0.29 m tall and "
                                 "the inside 0.18 m, so drawer_1 could not be closed"):
            TransportAction("breakfast-cereal", target=target).perform(ctx)
        assert (dict(ctx.scene.world_joint_positions()), ctx.time_s,
                ctx.scene.object_pose("breakfast-cereal")) == before
        # what fits is carried in, and the drawer closed again
        TransportAction("cup", target=_target(ctx, "drawer_2", 0.18, 0.0)).perform(ctx)
        assert ctx.scene.container_of("cup") is ctx.scene.containers["drawer_2"]


def _check(ctx, item: str, x: float, y: float, yaw: float | None) -> None:
    drawer = ctx.scene.containers["drawer_1"]
    target = _target(ctx, "drawer_1", x, y)
    spots = PlacingLocation(as_object(item, ctx), target=target).spots(ctx)
    check_fits(ctx, item, target, spots, drawer, yaw)


def test_the_footprint_fits_at_some_yaw_of_the_places_tried() -> None:
    with simulated_robot(load_setup("v1"), backend="kinematic") as ctx:
        # a spoon (16 x 3 cm) 3 cm from the drawer's front wall: along the wall only
        _check(ctx, "spoon", 0.06, 0.0, None)
        _check(ctx, "spoon", 0.06, 0.0, math.pi / 2)
        _check(ctx, "spoon", 0.06, 0.0, -math.pi / 2)  # (the same, by its symmetry)
        with pytest.raises(PlacementFailed, match="would stick out of the inside turned to "
                                                  "yaw 0.00 rad"):
            _check(ctx, "spoon", 0.06, 0.0, 0.0)
        # a bowl (16 cm across) at the side wall: no turn helps, nor 3 cm further in
        _check(ctx, "bowl", 0.18, 0.11, None)
        with pytest.raises(PlacementFailed, match=r"bowl: it \(0.16 x 0.16 x 0.07 m\) does "
                                                  r"not fit in drawer_1 .* would stick out "
                                                  "of the inside at any yaw"):
            _check(ctx, "bowl", 0.18, 0.14, None)
