"""What a plan reports: the order it fetched in, its failures, its straight-line distance."""

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

    def add_leg(self, robot_xy, item_xy, goal_xy) -> None:
        self.straight_line_m += math.dist(robot_xy, item_xy) + math.dist(item_xy, goal_xy)
