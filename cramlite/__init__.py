"""cramlite: a lightweight, ROS-free robot plan executive in the style of PyCRAM.

The public API is importable from here; names are loaded on first use, so that
`from cramlite import make_strategy` imports no simulator (strategies and metrics stay
free of them).
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    # setups, the planning scene, backends
    "load_setup": "cramlite.world", "Setup": "cramlite.world",
    "PlanningScene": "cramlite.scene", "load_backend": "cramlite.backends",
    "World": "cramlite.backends.pybullet.world",
    # designators and execution
    "simulated_robot": "cramlite.designators", "RobotContext": "cramlite.designators",
    "ActionDesignator": "cramlite.designators",
    "ObjectDesignatorDescription": "cramlite.designators",
    "CostmapLocation": "cramlite.designators", "PlacingLocation": "cramlite.designators",
    "NavigateAction": "cramlite.designators", "PickUpAction": "cramlite.designators",
    "PlaceAction": "cramlite.designators", "ParkArmsAction": "cramlite.designators",
    "MoveTorsoAction": "cramlite.designators", "TransportAction": "cramlite.designators",
    "PlanFailure": "cramlite.designators", "ProcessModules": "cramlite.designators",
    "Sequential": "cramlite.designators", "TryInOrder": "cramlite.designators",
    "TryAll": "cramlite.designators", "Parallel": "cramlite.designators",
    "Repeat": "cramlite.designators", "Code": "cramlite.designators",
    "Retry": "cramlite.designators", "retry": "cramlite.designators",
    "Monitor": "cramlite.designators", "MonitorFired": "cramlite.designators",
    "RobotState": "cramlite.designators", "LookAtAction": "cramlite.designators",
    "DetectAction": "cramlite.designators",
    "SetGripperAction": "cramlite.designators", "PickAndPlaceAction": "cramlite.designators",
    "FetchAction": "cramlite.designators", "DeliverAction": "cramlite.designators",
    "OpenAction": "cramlite.designators.storage", "CloseAction": "cramlite.designators.storage",
    "PlanReport": "cramlite.plans",
    # strategies
    "Strategy": "cramlite.strategies", "Candidate": "cramlite.strategies",
    "make_strategy": "cramlite.strategies", "available_strategies": "cramlite.strategies",
    # trials and evaluation
    "TrialRunner": "cramlite.trial", "run_trial": "cramlite.trial",
    "load_episodes": "cramlite.evaluation.data", "evaluate": "cramlite.evaluation.evaluate",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'cramlite' has no attribute {name!r}")
