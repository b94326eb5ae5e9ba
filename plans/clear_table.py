"""Clearing the table: every item from the island back to a free spot on the counter, or,
if it was stored, back into its drawer or cupboard, where it was.

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
    """Stored items go back into their drawer or cupboard, where they were; the others to
    the counter (their own spot there first)."""
    goals = {spec.name: ({"target": spec.pose.xyz, "target_yaw": spec.pose.yaw}
                         if spec.container else
                         {"surface": COUNTER, "preferred": spec.pose.xyz
                          if spec.surface == COUNTER else None}) for spec in setup.items}
    return fetch_in_strategy_order(ctx, setup, strategy, goals, PlanReport())
