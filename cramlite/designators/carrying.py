"""Carrying more than one item: a transport split in its two halves.

`FetchAction` navigates to an item and picks it up with a free arm, and keeps it in hand
(the place it is bound for is checked before it is picked, as a transport checks it);
`DeliverAction` takes an item in hand to its goal and puts it down. Between them the
robot may fetch another item with its other hand: every motion of that is planned and
checked with the first item held (it moves with its arm and is checked against the
kitchen, the items and the rest of the robot, the other arm included).
"""

from __future__ import annotations

from dataclasses import dataclass

from cramlite.designators.actions import (
    ParkArmsAction,
    TransportAction,
    Vec3,
    _closed_now,
    check_resting_place,
)
from cramlite.designators.context import RobotContext
from cramlite.designators.failures import PlacementFailed, PlanFailure
from cramlite.designators.locations import ReachablePose
from cramlite.designators.objects import as_object


@dataclass(frozen=True)
class Fetched:
    """What `FetchAction` returns: the item in hand, the arm holding it, where it was
    and from where it was taken, and the delivery its fetch step planned (if any)."""

    obj: str
    arm: str
    origin: Vec3
    picked_from: ReachablePose
    planned: tuple[Vec3, ReachablePose] | None = None


@dataclass
class FetchAction(TransportAction):
    """Navigate to an object and pick it up with a free arm; it stays in hand. Its goal
    (`target` or `surface`, as for TransportAction) is where it will be delivered: only
    an arm and grasp that can put it down there are used. An item in closed storage is
    taken out (the container opened with a free hand and closed again). Returns a
    `Fetched`."""

    def execute(self, ctx: RobotContext) -> Fetched:
        from cramlite.designators.storage import (
            CloseAction,
            OpenAction,
            container_at,
            container_of,
            is_open,
        )

        obj = as_object(self.object, ctx)
        if self.target is not None and container_at(ctx, self.target)[0] is not None:
            raise PlacementFailed("FetchAction delivers to open places only; a goal inside "
                                  "a drawer or cupboard needs TransportAction", obj=obj.name)
        ParkArmsAction().perform(ctx)
        source = container_of(ctx, obj.name)
        if source is not None and not is_open(ctx, source):
            OpenAction(source.name).perform(ctx)
        origin, _ = obj.pose(ctx)
        picked_from, planned = self._fetch(ctx, obj, self.target)
        if source is not None and not ctx.options.keep_containers_open:
            _closed_now(ctx, CloseAction, source)
        arm = next(a for a, h in ctx.holding.items() if h.obj == obj.name)
        return Fetched(obj.name, arm, origin, picked_from, planned)

    def validate(self, ctx: RobotContext, result: object = None) -> None:
        name = as_object(self.object, ctx).name
        if not any(h.obj == name for h in ctx.holding.values()):
            raise PlacementFailed("not in hand after the fetch", obj=name)


@dataclass
class DeliverAction(TransportAction):
    """Take an object in hand to its goal (`target` or `surface`) and put it down: first
    where its fetch planned (`fetched`), then other spots and base poses, best first. If
    it cannot be put down, it is put back where `fetched` says it was taken from (or let
    go of), and the failure is raised. Returns where it came to rest."""

    fetched: Fetched | None = None  #: what FetchAction returned for it

    def execute(self, ctx: RobotContext) -> Vec3:
        obj = as_object(self.object, ctx)
        if not any(h.obj == obj.name for h in ctx.holding.values()):
            raise PlacementFailed("not in hand: fetch it first", obj=obj.name)
        if self.target is not None:
            check_resting_place(ctx, obj.name, self.target)
        ParkArmsAction().perform(ctx)
        fetched = self.fetched if self.fetched is not None and \
            self.fetched.obj == obj.name else None
        try:
            self._deliver(ctx, obj, fetched.planned if fetched else None, self.target)
        except PlanFailure:
            if fetched is not None:
                self._put_back(ctx, obj, fetched.origin, fetched.picked_from)
            raise
        return obj.pose(ctx)[0]
