"""Setting the table: every item of the setup to its target on the island.

Generic: park the arms and raise the torso, then, while items remain, ask the ordering
strategy which item is next (from the robot's current position; the last item needs no
question) and transport it. A failed item is reported and the plan goes on.
"""

from __future__ import annotations

import math

from cramlite.plans.report import PlanReport

from cramlite.designators import (
    MoveTorsoAction,
    ObjectDesignatorDescription,
    ParkArmsAction,
    PlanFailure,
    RobotContext,
    TransportAction,
)
from cramlite.designators.actions import RESTING_HEIGHT_TOLERANCE_M
from cramlite.designators.carrying import DeliverAction, FetchAction, Fetched
from cramlite.designators.locations import IDEAL_STANDOFF_M, held
from cramlite.designators.storage import CloseAction, container_at, container_of, is_open
from cramlite.errors import UserInputError
from cramlite.motion.ik import ARMS
from cramlite.strategies import Candidate, Strategy
from cramlite.strategies.base import checked_batch, checked_choice, checked_reset
from cramlite.world.pr2 import HAND_PAYLOAD_KG, TORSO_UP_M
from cramlite.world.setup import Setup


def item_candidate(ctx: RobotContext, setup: Setup, name: str,
                   then_at: tuple[float, float, float]) -> Candidate:
    """What the strategy sees of an item: where it is now, its k category and c flag,
    where the robot will stand to take it (`fetch_at`) and after delivering it
    (`then_at`)."""
    spec = setup.item(name)
    (x, y, z), _ = ctx.scene.object_pose(name)
    container = container_of(ctx, name)  # closed storage now: the OPM's c applies
    return Candidate(name=name, position=(x, y, z), category=spec.category,
                     contained=container is not None and not is_open(ctx, container),
                     then_at=then_at,
                     fetch_at=fetch_estimate(robot_position(ctx), (x, y)),
                     metadata={"type": spec.type, "aliases": spec.aliases})


def fetch_estimate(robot: tuple[float, float, float], item_xy: tuple[float, float],
                   ) -> tuple[float, float, float]:
    """Where the robot will stand to pick the item up, estimated without planning: at the
    location designator's preferred stand-off from the item, on the side it comes from
    (its candidates are ranked by stand-off and by how far the robot has to drive)."""
    dx, dy = robot[0] - item_xy[0], robot[1] - item_xy[1]
    distance = math.hypot(dx, dy)
    if distance <= IDEAL_STANDOFF_M:
        return robot
    scale = IDEAL_STANDOFF_M / distance
    return (item_xy[0] + dx * scale, item_xy[1] + dy * scale, 0.0)


def robot_position(ctx: RobotContext) -> tuple[float, float, float]:
    x, y, _ = ctx.scene.base
    return (x, y, 0.0)


def fetch_in_strategy_order(ctx: RobotContext, setup: Setup, strategy: Strategy,
                            goals: dict[str, dict], report: PlanReport) -> PlanReport:
    """The loop both plans share: ask, carry, record. `goals` maps each item to the
    TransportAction arguments that say where it goes (`target` or `surface`). With the
    plan option `carry` 2 (`--carry 2`) the strategy is asked for a batch, one item per
    hand (`choose_batch`), fetched one after the other and then delivered in that order;
    an item that cannot share a trip (see `shares_a_trip`) is carried alone. An item whose
    transport failed where it stands is tried once more when the others are done, if any
    other item moved since (see `can_try_again`); the order reports the strategy's
    choices, once each, and the trips every trip made (the failed one too)."""
    remaining = [n for n in setup.baseline_order if n in goals]
    carry = carry_option(ctx)
    try:
        ParkArmsAction().perform(ctx)
        MoveTorsoAction(TORSO_UP_M, while_driving=True).perform(ctx)  # (with the first drive)
    except PlanFailure as failure:  # stuck where it stands: nothing can be fetched
        ctx.note(f"failed: {failure}")
        report.failures.append(failure)
        return report

    def then_at(name: str) -> tuple[float, float, float]:
        goal = goals[name].get("target") or goals[name].get("preferred")
        if goal is None:  # somewhere on a surface: its middle
            surf = ctx.scene.surface(goals[name]["surface"])
            goal = ((surf.x_min + surf.x_max) / 2, (surf.y_min + surf.y_max) / 2)
        return (goal[0], goal[1], 0.0)

    checked_reset(strategy, [item_candidate(ctx, setup, n, then_at(n)) for n in remaining],
                  robot_position(ctx))
    alone: set[str] = set()  # (a second fetch failed with one hand full: alone next time)
    #: (item, failure, where every item stood then): failed where it stands, tried again
    #: when the rest is done
    again: list[tuple[str, PlanFailure, dict]] = []
    while remaining:
        candidates = [item_candidate(ctx, setup, n, then_at(n)) for n in remaining]
        here = robot_position(ctx)
        if len(candidates) == 1:
            batch = candidates
        elif carry == 1:
            batch = [checked_choice(strategy, candidates, here)]
        else:
            batch = checked_batch(strategy, candidates, here, min(carry, len(ARMS)))
            shared = [c for c in batch if c.name not in alone and
                      shares_a_trip(ctx, c.name, goals[c.name])]
            batch = batch[:1] if batch[0] not in shared else shared
        names = [c.name for c in batch]
        report.order.extend(names)
        report.trips.append(names)
        for name in names:
            remaining.remove(name)
        if len(batch) == 1:
            try:
                _transport_alone(ctx, names[0], goals)
            except PlanFailure as failure:
                _failed(ctx, names[0], failure, report, again)
        else:
            back = _carry_together(ctx, names, goals, report, again)
            for name in back:  # (not fetched: asked about again, carried alone)
                report.order.remove(name)
                report.trips[-1].remove(name)
                remaining.append(name)
                alone.add(name)
            if not report.trips[-1]:
                report.trips.pop()
        report.add_trip(here[:2], [c.position[:2] for c in batch if c.name in report.order],
                        [ctx.scene.object_pose(c.name)[0][:2] for c in batch
                         if c.name in report.order])
    for name, failure, then in again:
        # (its failure stands in fetch order: taken back if this try succeeds, replaced if
        # it fails again)
        at = next(k for k, f in enumerate(report.failures) if f is failure)
        if not _others_moved(ctx, name, then):  # the same world: the same failure
            ctx.note(f"not trying {name} again: nothing has moved since it failed")
            continue
        ctx.note(f"trying {name} again (other items moved since it failed)")
        here = robot_position(ctx)
        position = ctx.scene.object_pose(name)[0][:2]
        try:
            _transport_alone(ctx, name, goals)
            ctx.note(f"{name}: done at the second try")
        except PlanFailure as second:
            ctx.note(f"failed again: {second}")
            report.failures[at] = second
            continue
        del report.failures[at]
        report.trips.append([name])
        report.add_trip(here[:2], [position], [ctx.scene.object_pose(name)[0][:2]])
    for step in [*(CloseAction(name) for name in list(ctx.opened)), ParkArmsAction()]:
        try:  # whatever it opened is closed again, and the arms are tucked
            step.perform(ctx)
        except PlanFailure as failure:
            ctx.note(f"failed: {failure}")
            report.failures.append(failure)
    return report


def _transport_alone(ctx: RobotContext, name: str, goals: dict[str, dict]) -> None:
    """Fetch one item and put it where `goals` says (PlanFailure if it cannot)."""
    TransportAction(ObjectDesignatorDescription(names=[name]), **goals[name]).perform(ctx)


def _failed(ctx: RobotContext, name: str, failure: PlanFailure, report: PlanReport,
            again: list[tuple[str, PlanFailure, dict]], then: dict | None = None) -> None:
    """A transport failed: reported (in fetch order), and, if it may be tried again, kept
    for the end, with where the items stood `then` (by default now; a trip carrying two:
    when it began, as the item delivered before this one may be what was in its way)."""
    ctx.note(f"failed: {failure}")
    report.failures.append(failure)
    if can_try_again(ctx, name):
        again.append((name, failure, then if then is not None else _positions(ctx)))


def _positions(ctx: RobotContext) -> dict[str, tuple[float, float, float]]:
    return {n: ctx.scene.object_pose(n)[0] for n in ctx.scene.items}


def _others_moved(ctx: RobotContext, name: str, then: dict) -> bool:
    """Has an item other than `name` moved by more than 1 cm since `then`?"""
    return any(math.dist(p, then[n]) > 0.01 for n, p in _positions(ctx).items()
               if n != name and n in then)


def can_try_again(ctx: RobotContext, name: str) -> bool:
    """After a failed transport, may the item be tried again later? If it is out of the
    hand and stands on something (a surface, or in a drawer or cupboard): where it was, or
    put back. (A failure of its own, with nothing else moved, often has another item in
    the way of every arm that could take it.)"""
    if name in held(ctx):
        return False
    point, _ = ctx.scene.object_pose(name)
    return ctx.scene.support_under(point, RESTING_HEIGHT_TOLERANCE_M) is not None


def carry_option(ctx: RobotContext) -> int:
    """How many items the plan carries at once: the plan option `carry` (default 1)."""
    carry = ctx.plan_options.get("carry", 1)
    if isinstance(carry, bool) or not isinstance(carry, int) or not 1 <= carry <= len(ARMS):
        raise UserInputError(f"expected 1 or {len(ARMS)} (one item per hand), got {carry!r}",
                             field="--carry")
    return carry


def shares_a_trip(ctx: RobotContext, name: str, goal: dict) -> bool:
    """Can the item be carried with another? Not if it lies in a drawer or cupboard or
    goes into one (opening and closing needs a free hand), nor if it is heavier than one
    of the PR2's hands can hold (`HAND_PAYLOAD_KG`): those are carried alone."""
    if container_of(ctx, name) is not None:
        return False
    target = goal.get("target")
    if target is not None and container_at(ctx, target)[0] is not None:
        return False
    return ctx.scene.items[name].model.mass_kg <= HAND_PAYLOAD_KG


def _carry_together(ctx: RobotContext, names: list[str], goals: dict[str, dict],
                    report: PlanReport, again: list[tuple[str, PlanFailure, dict]],
                    ) -> list[str]:
    """Fetch each item with a free hand, then deliver them in the same order. A failed
    first fetch is a failure of that item (see `_failed`); after it, and after a failed
    later fetch, the items not yet fetched are returned (the plan asks about them again
    and carries them alone)."""
    fetched: list[Fetched] = []
    then = _positions(ctx)
    for index, name in enumerate(names):
        try:
            fetched.append(FetchAction(name, **goals[name]).perform(ctx))
        except PlanFailure as failure:
            if fetched:
                ctx.note(f"could not fetch {name} with one hand full ({failure}); it is "
                         "carried alone later")
                back = names[index:]
            else:
                _failed(ctx, name, failure, report, again, then)
                back = names[index + 1:]
            break
    else:
        back = []
    for item in fetched:
        try:
            DeliverAction(item.obj, fetched=item, **goals[item.obj]).perform(ctx)
        except PlanFailure as failure:
            _failed(ctx, item.obj, failure, report, again, then)
    return back


def set_table(ctx: RobotContext, setup: Setup, strategy: Strategy) -> PlanReport:
    goals = {spec.name: {"target": spec.target.xyz, "target_yaw": spec.target.yaw}
             for spec in setup.items}
    return fetch_in_strategy_order(ctx, setup, strategy, goals, PlanReport())
