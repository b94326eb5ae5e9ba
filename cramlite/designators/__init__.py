"""Designators (object, location, action, motion) and the plan language; the process
modules they command are the backends' (`cramlite.backends`)."""

from cramlite.backends.base import ProcessModules
from cramlite.designators.actions import (
    MoveTorsoAction,
    NavigateAction,
    ParkArmsAction,
    PickAndPlaceAction,
    PickUpAction,
    PlaceAction,
    SetGripperAction,
    TransportAction,
)
from cramlite.designators.carrying import DeliverAction, FetchAction, Fetched
from cramlite.designators.context import ExecutionOptions, RobotContext, simulated_robot
from cramlite.designators.failures import (
    ContainerManipulationFailed,
    GraspFailed,
    IKFailed,
    MotionPlanningFailed,
    NavigationFailed,
    NoPathFound,
    ObjectNotFound,
    ObjectUnreachable,
    PlacementFailed,
    PlanFailure,
)
from cramlite.designators.head import LookAtAction
from cramlite.designators.language import (
    Code,
    Monitor,
    Parallel,
    Repeat,
    Retry,
    Sequential,
    TryAll,
    TryInOrder,
    retry,
)
from cramlite.designators.locations import CostmapLocation, PlacingLocation, ReachablePose
from cramlite.designators.monitors import MonitorFired, RobotState
from cramlite.designators.motions import (
    AttachMotion,
    DetachMotion,
    MoveArmJointsMotion,
    MoveGripperMotion,
    MoveMotion,
    MoveTCPMotion,
    MoveTorsoMotion,
)
from cramlite.designators.objects import ObjectDesignator, ObjectDesignatorDescription
from cramlite.designators.perception import DetectAction
from cramlite.designators.tasks import ActionDesignator

__all__ = [
    "ActionDesignator", "AttachMotion", "ContainerManipulationFailed", "CostmapLocation",
    "DetachMotion", "ExecutionOptions",
    "GraspFailed", "IKFailed", "MotionPlanningFailed", "MoveArmJointsMotion", "MoveGripperMotion",
    "MoveMotion", "MoveTCPMotion",
    "MoveTorsoAction",
    "MoveTorsoMotion", "NavigateAction", "NavigationFailed", "NoPathFound", "ObjectDesignator",
    "ObjectDesignatorDescription", "ObjectNotFound", "ObjectUnreachable", "ParkArmsAction",
    "PickUpAction", "PlaceAction", "PlacementFailed", "PlacingLocation", "PlanFailure",
    "ProcessModules", "ReachablePose", "RobotContext", "Sequential",
    "TransportAction", "TryInOrder", "simulated_robot", "Code", "Monitor", "MonitorFired",
    "Parallel", "Repeat", "Retry", "RobotState", "TryAll", "retry", "LookAtAction",
    "SetGripperAction", "PickAndPlaceAction", "DetectAction", "FetchAction", "DeliverAction",
    "Fetched",
]
