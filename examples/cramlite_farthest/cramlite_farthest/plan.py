"""Fetch two: the robot looks at each of the two items the strategy picks first and takes
it to its target, then looks into drawer_1 (opens it, looks in, notes what it detects,
closes it again). A plan written with designators.

    cramlite run c1 --plan ./examples/fetch_two.py:fetch_two
    cramlite bench --plan ./examples/fetch_two.py:fetch_two --setups v1,c1 --trials 2

A plan is a function `(ctx, setup, strategy) -> PlanReport`: `ctx` is the robot (its
planning scene, its process modules, the task tree), `setup` the setup file loaded,
`strategy` the ordering strategy of the trial. It says what success means by setting
`report.success`; a `PlanFailure` it lets escape is recorded as the trial's failure.
"""

from __future__ import annotations

import math

from cramlite.plans.set_table import item_candidate, robot_position

from cramlite import (
    CloseAction,
    Code,
    DetectAction,
    LookAtAction,
    MoveTorsoAction,
    OpenAction,
    ParkArmsAction,
    PlanFailure,
    PlanReport,
    RobotContext,
    Setup,
    Strategy,
    TransportAction,
    TryInOrder,
)

#: How many items it fetches.
COUNT = 2


def fetch_two(ctx: RobotContext, setup: Setup, strategy: Strategy) -> PlanReport:
    """Fetch the strategy's first two items to their targets, then open and close
    drawer_1."""
    report = PlanReport()
    ParkArmsAction().perform(ctx)
    MoveTorsoAction(0.25).perform(ctx)
    targets = {spec.name: spec.target for spec in setup.items}
    remaining = list(setup.baseline_order)
    strategy.reset([item_candidate(ctx, setup, n, targets[n].xyz) for n in remaining],
                   robot_position(ctx))
    for _ in range(min(COUNT, len(remaining))):
        candidates = [item_candidate(ctx, setup, n, targets[n].xyz) for n in remaining]
        chosen = strategy.choose(candidates, robot_position(ctx))
        remaining.remove(chosen.name)
        report.order.append(chosen.name)
        target = targets[chosen.name]
        # (the straight legs robot -> item -> target, as the built-in plans report them)
        report.add_leg(robot_position(ctx)[:2], chosen.position[:2], target.xyz[:2])
        try:
            # the head turns to it first; an item behind the head's reach (it pans
            # 172 degrees each way) is fetched without the look
            TryInOrder([LookAtAction(chosen.name), Code(lambda ctx: None)]).perform(ctx)
            TransportAction(chosen.name, target=target.xyz, target_yaw=target.yaw).perform(ctx)
        except PlanFailure as failure:  # recorded; the plan goes on with the next item
            report.failures.append(failure)
    for name in list(ctx.opened):  # whatever the transports opened is closed again
        CloseAction(name).perform(ctx)
    if "drawer_1" in ctx.scene.containers:
        OpenAction("drawer_1").perform(ctx)
        inside = ctx.scene.containers["drawer_1"]
        (x, y, z), _ = ctx.scene.link_frame(inside.inside_link)
        LookAtAction((x, y, z)).perform(ctx)  # into the open drawer
        seen = DetectAction().perform(ctx)  # what the camera sees there and around
        ctx.note(f"seen in and around drawer_1: {', '.join(sorted(seen)) or 'nothing'}")
        CloseAction("drawer_1").perform(ctx)
    ParkArmsAction().perform(ctx)
    # success: both items stand at their targets and every container is closed again
    at_targets = all(math.dist(ctx.scene.object_pose(name)[0][:2], targets[name].xyz[:2])
                     < 0.05 for name in report.order)
    closed = all(not ctx.scene.is_open(c) for c in ctx.scene.containers.values())
    report.success = at_targets and closed and not report.failures
    return report
