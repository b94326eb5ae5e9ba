"""What a plan reports: the order it fetched in, its failures, its straight-line distance,
and (a user's plan) whether it succeeded."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

from cramlite.designators import PlanFailure


@dataclass
class PlanReport:
    order: list[str] = field(default_factory=list)
    failures: list[PlanFailure] = field(default_factory=list)
    #: Sum over steps of straight xy distances robot -> item -> where it was put (None:
    #: not reported; the built-in plans report every trip, a user's plan with `add_leg`).
    straight_line_m: float | None = None
    #: A user's plan's own verdict (None: no failures = success). The built-in plans leave
    #: it None: the trial checks where the items ended.
    success: bool | None = None
    #: The items fetched together on each trip, in fetch order (one each with carry 1).
    trips: list[list[str]] = field(default_factory=list)

    def __repr__(self) -> str:
        verdict = "" if self.success is None else f", success={self.success}"
        legs = "None" if self.straight_line_m is None else f"{self.straight_line_m:.2f}"
        return (f"PlanReport(order={self.order}, failures={len(self.failures)}, "
                f"straight_line_m={legs}{verdict})")

    def add_leg(self, robot_xy, item_xy, goal_xy) -> None:
        self.straight_line_m = (self.straight_line_m or 0.0) + math.dist(robot_xy, item_xy) \
            + math.dist(item_xy, goal_xy)

    def add_trip(self, robot_xy, item_xys, goal_xys) -> None:
        """A trip's straight legs: robot -> each item in turn -> each goal in turn."""
        points = [robot_xy, *item_xys, *goal_xys]
        self.straight_line_m = (self.straight_line_m or 0.0) + sum(
            math.dist(a, b) for a, b in itertools.pairwise(points))
