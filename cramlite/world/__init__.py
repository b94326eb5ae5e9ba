"""World layer: PyBullet worlds, the PR2 model, setup files."""

from cramlite.world.bodies import RobotBody, WorldObject
from cramlite.world.setup import ItemSpec, Pose, Setup, load_setup
from cramlite.world.world import Snapshot, Surface, World

__all__ = ["ItemSpec", "Pose", "RobotBody", "Setup", "Snapshot", "Surface", "World",
           "WorldObject", "load_setup"]
