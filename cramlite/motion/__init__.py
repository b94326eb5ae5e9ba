"""Motion layer: arm IK (Pinocchio) and base paths (OMPL) for the PR2."""

from cramlite.motion.base_planner import BaseMotionPlanner, BasePath, BasePlannerOptions
from cramlite.motion.footprint import FootprintChecker, OccupancyMap
from cramlite.motion.ik import ArmIK, IKOptions, IKSolution, arm_ik

__all__ = ["ArmIK", "BaseMotionPlanner", "BasePath", "BasePlannerOptions", "FootprintChecker",
           "IKOptions", "IKSolution", "OccupancyMap", "arm_ik"]
