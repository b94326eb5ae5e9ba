"""What a plan reports: the order it fetched in, its failures, its straight-line distance,
and (a user's plan) whether it succeeded."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from cramlite.designators import PlanFailure


@dataclass
class PlanReport:
    order: list[str] = field(default_factory=list)
    failures: list[PlanFailure] = field(default_factory=list)
    #: Sum over steps of straight xy distances robot -> item -> where it was put.
    straight_line_m: float = 0.0
    #: A user's plan's own verdict (None: no failures = success). The built-in plans leave
    #: it None: the trial checks where the items ended.
    success: bool | None = None

    def __repr__(self) -> str:
        verdict = "" if self.success is None else f", success={self.success}"
        return (f"PlanReport(order={self.order}, failures={len(self.failures)}, "
                f"straight_line_m={self.straight_line_m:.2f}{verdict})")

    def add_leg(self, robot_xy, item_xy, goal_xy) -> None:
        self.straight_line_m += math.dist(robot_xy, item_xy) + math.dist(item_xy, goal_xy)
