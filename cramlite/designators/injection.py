"""Seeded failure injection (as pyrobosim offers): process-module executions fail now and
then with the typed failure a robot would raise, so that recovery is exercised.

`--inject grasp=0.1,navigate=0.05,detect=0.1` gives a probability per attempt:
- `navigate`: a drive is refused before the base moves (NavigationFailed: localisation
  lost); the navigation falls through to its next base pose;
- `grasp`: the item slips out as the fingers close (GraspFailed, at `attach`); the arm
  opens its gripper, backs off to the pre-grasp and the pick-up falls through to its next
  candidate;
- `detect`: the camera sees nothing this time (DetectAction reports no item).
Draws come from a random stream of their own, seeded by the trial's seed, so planning's
random choices do not shift and the same seed gives the same failures.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np

from cramlite.backends.base import BasePose, ProcessModules, StateObserver
from cramlite.designators.failures import GraspFailed, NavigationFailed
from cramlite.errors import UserInputError
from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.scene.transforms import Pose

KINDS = ("grasp", "navigate", "detect")


def parse_inject(text: str | None, field: str = "--inject") -> dict[str, float]:
    """`grasp=0.1,navigate=0.05` -> {kind: probability}; every part checked."""
    if not text:
        return {}
    out: dict[str, float] = {}
    for part in (p.strip() for p in text.split(",")):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or name not in KINDS:
            raise UserInputError(f"expected KIND=PROBABILITY with KIND one of "
                                 f"{', '.join(KINDS)}, got {part!r}", field=field)
        try:
            probability = float(value)
        except ValueError:
            probability = float("nan")
        if not 0.0 <= probability <= 1.0:
            raise UserInputError(f"{name}: expected a probability in [0, 1], got {value!r}",
                                 field=field)
        if name in out:
            raise UserInputError(f"{name} is given twice", field=field)
        out[name] = probability
    return out


def inject_text(probabilities: dict[str, float]) -> str:
    """The canonical spelling (sorted by kind): what a results row keys a trial by."""
    return ",".join(f"{k}={probabilities[k]:g}" for k in KINDS if k in probabilities)


class Injector:
    """Draws whether an attempt fails, from a stream of its own; counts what it injected."""

    def __init__(self, probabilities: dict[str, float], seed: int):
        self.probabilities = dict(probabilities)
        self.rng = np.random.default_rng([seed, 4])
        self.injected: Counter[str] = Counter()

    def fails(self, kind: str) -> bool:
        p = self.probabilities.get(kind, 0.0)
        if p <= 0.0:
            return False
        if self.rng.random() < p:
            self.injected[kind] += 1
            return True
        return False


class InjectingModules(ProcessModules):
    """Process modules that pass every call on to `inner`, but fail executions as the
    injector draws."""

    def __init__(self, inner: ProcessModules, injector: Injector):
        self.inner = inner
        self.injector = injector

    def _drive_fails(self) -> None:
        if self.injector.fails("navigate"):
            raise NavigationFailed("injected: the base stopped before it moved (localisation "
                                   "lost)")

    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        self._drive_fails()
        self.inner.execute_base_trajectory(trajectory, on_state)

    def execute_parallel(self, base: BaseTrajectory, joints: JointTrajectory,
                         on_state: StateObserver = None) -> None:
        self._drive_fails()
        self.inner.execute_parallel(base, joints, on_state)

    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        self.inner.execute_joint_trajectory(trajectory, on_state)

    def attach(self, arm: str, obj: str) -> None:
        if self.injector.fails("grasp"):
            raise GraspFailed("injected: it slipped out as the fingers closed", obj=obj)
        self.inner.attach(arm, obj)

    def detach(self, arm: str, obj: str) -> None:
        self.inner.detach(arm, obj)

    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        self.inner.settle(seconds, objects)

    def release_all(self) -> None:
        self.inner.release_all()

    def base_pose(self) -> BasePose:
        return self.inner.base_pose()

    def joint_positions(self, names: Sequence[str]) -> dict[str, float]:
        return self.inner.joint_positions(names)

    def world_joint_positions(self) -> dict[str, float]:
        return self.inner.world_joint_positions()

    def object_pose(self, obj: str) -> Pose:
        return self.inner.object_pose(obj)

    def tool_pose(self, arm: str) -> Pose:
        return self.inner.tool_pose(arm)

    def simulator_report(self) -> dict[str, float]:
        return self.inner.simulator_report()
