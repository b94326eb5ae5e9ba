"""Clearing the table: every item from the island back to a free spot on the counter.

The same designators and loop as setting the table, no new motion code: only the goals
differ (a surface instead of a target; the item's spot in the setup is preferred).
"""

from __future__ import annotations

from cramlite.plans.report import PlanReport
from cramlite.plans.set_table import fetch_in_strategy_order

from cramlite.designators import RobotContext
from cramlite.strategies import Strategy
from cramlite.world.setup import Setup

COUNTER = "counter"


def clear_table(ctx: RobotContext, setup: Setup, strategy: Strategy) -> PlanReport:
    goals = {spec.name: {"surface": COUNTER, "preferred": spec.pose.xyz
                         if spec.surface == COUNTER else None} for spec in setup.items}
    return fetch_in_strategy_order(ctx, setup, strategy, goals, PlanReport())
