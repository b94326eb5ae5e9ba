"""The failure taxonomy of plans: one root, `PlanFailure`, and seven kinds.

Each failure carries the object it concerns, the reason, and what was tried before it
escaped (base poses, arms, grasps, placements), so a user can see why a plan gave up.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from cramlite.errors import bounded_text

#: The most entries of `tried` kept in a results row (each cut to 400 characters).
TRIED_LIMIT = 50


def said_once(entries: Sequence[str]) -> list[str]:
    """Entries in their order, each once, with how often it was tried where more than
    once ("could not put it down at the goal (9 times)")."""
    counts: dict[str, int] = {}
    for entry in entries:
        counts[entry] = counts.get(entry, 0) + 1
    return [f"{e} ({n} times)" if n > 1 else e for e, n in counts.items()]


class PlanFailure(Exception):
    """A plan could not achieve something in the world (as opposed to a bug or bad input)."""

    kind = "plan failure"

    def __init__(self, reason: str, obj: str | None = None, tried: Sequence[str] = ()):
        self.object = obj
        self.reason = reason
        self.tried = list(tried)
        text = f"{obj}: {reason}" if obj else reason
        if self.tried:
            text += f" (tried: {'; '.join(said_once(self.tried))})"
        super().__init__(text)

    def as_dict(self) -> dict[str, object]:
        tried = [bounded_text(str(t), 400) for t in self.tried[:TRIED_LIMIT]]
        if len(self.tried) > TRIED_LIMIT:
            tried.append(f"... and {len(self.tried) - TRIED_LIMIT} more")
        return {"item": self.object, "type": type(self).__name__,
                "message": bounded_text(str(self)), "tried": tried}


class ObjectNotFound(PlanFailure):
    kind = "object not found"


class ObjectUnreachable(PlanFailure):
    """No arm, grasp and base pose reaches the object (IK failed everywhere)."""

    kind = "object unreachable"


IKFailed = ObjectUnreachable


class NavigationFailed(PlanFailure):
    """No collision-free base path to the goal."""

    kind = "navigation failed"


NoPathFound = NavigationFailed


class GraspFailed(PlanFailure):
    kind = "grasp failed"


class PlacementFailed(PlanFailure):
    kind = "placement failed"


class MotionPlanningFailed(PlanFailure):
    """No collision-free arm (or torso, gripper) path to a configuration."""

    kind = "motion planning failed"


class ContainerManipulationFailed(PlanFailure):
    """A drawer or door could not be opened or closed (no base pose and arm can follow
    its handle, or the motion failed)."""

    kind = "container manipulation failed"


def finite_numbers(values: object, count: int, what: str) -> tuple[float, ...]:
    """`values` as `count` finite floats, or a ValueError naming `what` (a designator's
    argument that is no pose or point: a mistake in the plan, said where it is written)."""
    try:
        numbers = tuple(float(v) for v in values)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        numbers = ()
    if len(numbers) != count or not all(math.isfinite(v) for v in numbers):
        raise ValueError(f"{what}: expected {count} finite numbers, got {values!r}")
    return numbers
