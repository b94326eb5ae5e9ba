"""What a plan reports: the order it fetched in, its failures, its straight-line distance,
and (a user's plan) whether it succeeded."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

from cramlite.designators import PlanFailure


class _NotReported(float):
    """0.0 that says no straight-line leg was added (a sum with it is a plain float)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "NOT_REPORTED"


#: The straight-line legs of a report nothing was added to (0.0 in any arithmetic).
NOT_REPORTED = _NotReported(0.0)


@dataclass
class PlanReport:
    order: list[str] = field(default_factory=list)
    failures: list[PlanFailure] = field(default_factory=list)
    #: Sum over steps of straight xy distances robot -> item -> where it was put (`add_leg`,
    #: `add_trip`, or added to directly). Until something is added it is `NOT_REPORTED`, a
    #: 0.0 that remembers it: a user's plan that adds none reports none (`legs_m`).
    straight_line_m: float = NOT_REPORTED
    #: A user's plan's own verdict (None: no failures = success). The built-in plans leave
    #: it None: the trial checks where the items ended.
    success: bool | None = None
    #: The items fetched together on each trip, in fetch order (one each with carry 1);
    #: a trip that failed is one, and an item tried again at the end is in a trip again.
    trips: list[list[str]] = field(default_factory=list)

    def __repr__(self) -> str:
        verdict = "" if self.success is None else f", success={self.success}"
        return (f"PlanReport(order={self.order}, failures={len(self.failures)}, "
                f"straight_line_m={self.straight_line_m:.2f}{verdict})")

    def legs_m(self) -> float | None:
        """The straight-line legs reported, None if none were."""
        return None if isinstance(self.straight_line_m, _NotReported) \
            else float(self.straight_line_m)

    def add_leg(self, robot_xy, item_xy, goal_xy) -> None:
        self.straight_line_m += math.dist(robot_xy, item_xy) + math.dist(item_xy, goal_xy)

    def add_trip(self, robot_xy, item_xys, goal_xys) -> None:
        """A trip's straight legs: robot -> each item in turn -> each goal in turn."""
        points = [robot_xy, *item_xys, *goal_xys]
        self.straight_line_m += sum(math.dist(a, b) for a, b in itertools.pairwise(points))
