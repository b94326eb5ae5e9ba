"""The recording backend: an example of the seam a real robot implements.

A robot's driver receives what these process modules receive: timed base trajectories
(x, y, yaw at each time), timed joint trajectories (joint names, positions at each time;
a drawer's or door's joint moving with the hand), gripper attach/detach commands. The
recording backend keeps every one of them, in order (`RecordingBackend.sent`, or as JSON
Lines with `write`), and otherwise executes kinematically (it must report what happened:
a real robot's modules would report its sensors).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from cramlite.backends.base import StateObserver
from cramlite.backends.kinematic import KinematicBackend, KinematicModules
from cramlite.motion.trajectory import BaseTrajectory, JointTrajectory
from cramlite.world.setup import Setup


class RecordingModules(KinematicModules):
    """Kinematic execution that keeps every command it receives."""

    def __init__(self, state, sent: list[dict[str, Any]]):
        super().__init__(state)
        self.sent = sent

    def execute_base_trajectory(self, trajectory: BaseTrajectory,
                                on_state: StateObserver = None) -> None:
        self.sent.append({"command": "base_trajectory",
                          "times": trajectory.times.round(6).tolist(),
                          "poses": trajectory.poses.round(6).tolist()})
        super().execute_base_trajectory(trajectory, on_state)

    def execute_joint_trajectory(self, trajectory: JointTrajectory,
                                 on_state: StateObserver = None) -> None:
        self.sent.append({"command": "joint_trajectory", "joints": list(trajectory.names),
                          "times": trajectory.times.round(6).tolist(),
                          "positions": trajectory.positions.round(6).tolist(),
                          "world": {k: v.round(6).tolist()
                                    for k, v in trajectory.world.items()}})
        super().execute_joint_trajectory(trajectory, on_state)

    def execute_parallel(self, base: BaseTrajectory, joints: JointTrajectory,
                         on_state: StateObserver = None) -> None:
        """One command: the base and the joints at the same times (a driver sends both)."""
        self.sent.append({"command": "parallel_trajectory", "joints": list(joints.names),
                          "times": base.times.round(6).tolist(),
                          "poses": base.poses.round(6).tolist(),
                          "positions": joints.positions.round(6).tolist()})
        sent, self.sent = self.sent, []  # (the steps below are this command's, not new ones)
        try:
            super().execute_parallel(base, joints, on_state)
        finally:
            self.sent = sent

    def attach(self, arm: str, obj: str) -> None:
        self.sent.append({"command": "attach", "arm": arm, "object": obj})
        super().attach(arm, obj)

    def detach(self, arm: str, obj: str) -> None:
        self.sent.append({"command": "detach", "arm": arm, "object": obj})
        super().detach(arm, obj)

    def settle(self, seconds: float, objects: Sequence[str] = ()) -> None:
        self.sent.append({"command": "settle", "seconds": seconds, "objects": list(objects)})


class RecordingBackend(KinematicBackend):
    """Kinematic execution, keeping every command a robot's driver would be sent."""

    name = "recording"

    def __init__(self, setup: Setup):
        super().__init__(setup)
        self.sent: list[dict[str, Any]] = []
        self.modules = RecordingModules(self.state, self.sent)

    def reset(self, poses=None) -> None:
        super().reset(poses)
        self.sent.clear()

    def write(self, path: str | Path) -> Path:
        """The commands received since the last reset, one JSON object per line."""
        path = Path(path)
        with path.open("w", encoding="utf-8") as handle:
            for record in self.sent:
                handle.write(json.dumps(record, separators=(",", ":")) + "\n")
        return path


__all__ = ["RecordingBackend", "RecordingModules"]
