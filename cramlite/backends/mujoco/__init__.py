"""The MuJoCo backend: a MuJoCo world per setup (composed from the same URDFs), kinematic
execution of the planned trajectories, physics for released items, offscreen images (EGL or
OSMesa). Raw MuJoCo calls stay inside this package. Needs `pip install 'cramlite[mujoco]'`
(mujoco-core with its rendering extra; Python >= 3.11)."""

from __future__ import annotations

import ctypes.util
import os

from cramlite.errors import UserInputError

# MuJoCo picks its OpenGL platform when it is first imported: headless EGL unless the user
# chose one (osmesa, or glfw with a display); with no EGL library at all, none (the
# backend runs, and a picture says in one line what is missing).
if "MUJOCO_GL" not in os.environ:
    os.environ["MUJOCO_GL"] = "egl" if ctypes.util.find_library("EGL") else "disable"
#: Why MuJoCo could not be imported with the OpenGL platform asked for ("" if it could):
#: it is imported again without one (the backend runs; a picture says this in one line).
GL_IMPORT_ERROR = ""
try:
    import mujoco  # noqa: F401  (every module of this package imports it after this)
except Exception as exc:  # a MUJOCO_GL it cannot use makes the import itself fail
    import sys

    GL_IMPORT_ERROR = f"{type(exc).__name__}: {exc}"
    asked = os.environ["MUJOCO_GL"]
    for name in [m for m in sys.modules if m.split(".")[0] in ("mujoco", "OpenGL")]:
        del sys.modules[name]
    os.environ["MUJOCO_GL"] = "disable"
    try:
        import mujoco  # noqa: F401
    except Exception as again:
        raise UserInputError(f"MuJoCo could not be imported ({type(again).__name__}: "
                             f"{again})", field="--backend") from None
    finally:
        os.environ["MUJOCO_GL"] = asked  # (what the user set, as messages name it)

from cramlite.backends.base import Backend, PhysicsRecord  # noqa: E402  (after MUJOCO_GL is settled)
from cramlite.scene.transforms import Pose  # noqa: E402
from cramlite.world.setup import Setup  # noqa: E402


class MujocoBackend(Backend):
    """Executes in a MuJoCo world loaded from the setup."""

    name = "mujoco"
    physics = True

    def __init__(self, setup: Setup):
        from cramlite.backends.mujoco.modules import MujocoModules
        from cramlite.backends.mujoco.world import MujocoWorld

        self.setup = setup
        self.world = MujocoWorld(setup)
        self.modules = MujocoModules(self.world)
        self._initial = self.world.snapshot()

    def reset(self, poses: dict[str, Pose] | None = None) -> None:
        self.modules.release_all()
        self.modules.physics = PhysicsRecord()  # (counted per trial)
        self.world.restore(self._initial)
        for name, (position, orientation) in (poses or {}).items():
            self.world.set_object_pose(name, position, orientation)
        self.world.forward()

    def close(self) -> None:
        self.world.close()


__all__ = ["MujocoBackend"]
