"""Monitors: a condition asked at every state of every motion while a plan's step runs.

`RobotContext` asks each active watch about every state of a trajectory as it is handed
to the process modules (the robot's time, base pose and joints at that state: the
states a position-controlled robot will pass through). At the first state where one
fires, the motion is cut there and brakes to rest along its own path within the joint
(or base) limits (`cramlite.motion.braking`); the braking states are executed and traced
like any others, and `MonitorFired` is raised. A fired watch stays fired: every further
motion inside the monitored step fails at once without moving, so the step's fallbacks
cannot carry on, until the `Monitor` ends and raises it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from cramlite.designators.failures import PlanFailure


class MonitorFired(PlanFailure):
    """A monitor's condition held: the motion in progress was stopped."""

    kind = "monitor fired"


@dataclass(frozen=True)
class RobotState:
    """What a monitor's condition sees of one state of a motion."""

    t: float  #: robot time (s) since the plan started
    base: tuple[float, float, float]  #: x, y, yaw
    joints: Mapping[str, float]  #: every joint of the robot (torso, arms, fingers)
    held: tuple[str, ...]  #: the items in the hands


Condition = Callable[[RobotState], bool]


@dataclass
class Watch:
    """An active monitor: its condition, and the failure once it fired."""

    condition: Condition
    name: str
    fired: MonitorFired | None = field(default=None)
    fired_at: float = 0.0  #: the robot time at which it fired

    def check(self, state: RobotState) -> bool:
        if self.condition(state):
            self.fired = MonitorFired(f"{self.name} fired at t = {state.t:.2f} s; the motion "
                                      "in progress braked to rest")
            self.fired_at = state.t
            return True
        return False

    def ran_to_its_end(self, end_t: float) -> None:
        """Say so where the motion was kept (it came to rest at its own end sooner than
        braking would have stopped it), not that it braked."""
        if self.fired is not None:
            self.fired = MonitorFired(
                f"{self.name} fired at t = {self.fired_at:.2f} s; the motion in progress was "
                f"near its end and came to rest there at t = {end_t:.2f} s (sooner than "
                "braking would)")


def first_firing(watches: list[Watch], t0: float, times: np.ndarray,
                 base_at: Callable[[int], tuple[float, float, float]],
                 joints_at: Callable[[int], Mapping[str, float]],
                 held: tuple[str, ...]) -> int | None:
    """The index of the first state at which a watch fires (it is marked fired)."""
    for i in range(len(times)):
        state = RobotState(t0 + float(times[i]), base_at(i), joints_at(i), held)
        if any(watch.check(state) for watch in watches):
            return i
    return None
