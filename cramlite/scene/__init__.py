"""The planning scene: Pinocchio and coal models of the robot, the kitchen and the items,
the planner's belief about them, and the questions planning asks (frames, surfaces,
containers, collisions: the robot against the kitchen, the items and itself)."""

from cramlite.scene.scene import Belief, Held, PlanningScene, SceneItem, Surface

__all__ = ["Belief", "Held", "PlanningScene", "SceneItem", "Surface"]
