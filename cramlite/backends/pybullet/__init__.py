"""The PyBullet backend: a PyBullet world per setup, kinematic execution, physics settling
and TinyRenderer images. Raw PyBullet calls stay inside this package."""

from __future__ import annotations

from cramlite.backends.base import Backend, PhysicsRecord
from cramlite.scene.transforms import Pose
from cramlite.world.setup import Setup


class PyBulletBackend(Backend):
    """Executes in a PyBullet world loaded from the setup (DIRECT, or the GUI)."""

    name = "pybullet"
    physics = True

    def __init__(self, setup: Setup, gui: bool = False, world=None):
        from cramlite.backends.pybullet.modules import SimulatedProcessModules
        from cramlite.backends.pybullet.world import World

        self.setup = setup
        self.world = world if world is not None else World.from_setup(setup, gui=gui)
        self._owned = world is None
        self.modules = SimulatedProcessModules(self.world)
        self._initial = self.world.snapshot()

    @classmethod
    def around(cls, world) -> PyBulletBackend:
        """A backend executing in a PyBullet `World` someone else loaded (and closes)."""
        return cls(world.setup, world=world)

    def reset(self, poses: dict[str, Pose] | None = None) -> None:
        self.modules.release_all()
        self.modules.physics = PhysicsRecord()  # (counted per trial)
        self.world.restore(self._initial)
        for name, (position, orientation) in (poses or {}).items():
            self.world.objects[name].set_pose(position, orientation)

    def close(self) -> None:
        if self._owned:
            self.world.close()


__all__ = ["PyBulletBackend"]
