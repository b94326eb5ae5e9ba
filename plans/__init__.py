"""Plans written with designators. Each takes (ctx, setup, strategy) and returns a report."""

from cramlite.plans.clear_table import clear_table
from cramlite.plans.report import PlanReport
from cramlite.plans.set_table import set_table

PLANS = {"set-table": set_table, "clear-table": clear_table}

__all__ = ["PLANS", "PlanReport", "clear_table", "set_table"]
