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
from cramlite.designators.locations import IDEAL_STANDOFF_M
from cramlite.designators.storage import CloseAction, container_of, is_open
from cramlite.strategies import Candidate, Strategy
from cramlite.strategies.base import checked_choice, checked_reset
from cramlite.world.pr2 import TORSO_UP_M
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
    """The loop both plans share: ask, transport, record. `goals` maps each item to the
    TransportAction arguments that say where it goes (`target` or `surface`)."""
    remaining = [n for n in setup.baseline_order if n in goals]
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
    while remaining:
        candidates = [item_candidate(ctx, setup, n, then_at(n)) for n in remaining]
        here = robot_position(ctx)
        chosen = candidates[0] if len(candidates) == 1 else \
            checked_choice(strategy, candidates, here)
        report.order.append(chosen.name)
        remaining.remove(chosen.name)
        try:
            TransportAction(ObjectDesignatorDescription(names=[chosen.name]),
                            **goals[chosen.name]).perform(ctx)
        except PlanFailure as failure:
            ctx.note(f"failed: {failure}")
            report.failures.append(failure)
        (x, y, _), _ = ctx.scene.object_pose(chosen.name)
        report.add_leg(here[:2], chosen.position[:2], (x, y))
    for step in [*(CloseAction(name) for name in list(ctx.opened)), ParkArmsAction()]:
        try:  # whatever it opened is closed again, and the arms are tucked
            step.perform(ctx)
        except PlanFailure as failure:
            ctx.note(f"failed: {failure}")
            report.failures.append(failure)
    return report


def set_table(ctx: RobotContext, setup: Setup, strategy: Strategy) -> PlanReport:
    goals = {spec.name: {"target": spec.target.xyz, "target_yaw": spec.target.yaw}
             for spec in setup.items}
    return fetch_in_strategy_order(ctx, setup, strategy, goals, PlanReport())
