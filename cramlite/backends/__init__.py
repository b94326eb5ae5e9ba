"""Backends: what executes a plan. Each implements `ProcessModules` (the seam a simulator
or a real robot implements) and loads its world from a setup; planning never touches it
(it asks the planning scene, which the process modules' reports keep up to date).

Built in: `pybullet` (physics settling, TinyRenderer images), `mujoco` (physics settling,
offscreen OpenGL images; `pip install 'cramlite[mujoco]'`), `kinematic` (no physics
engine, every Python) and `recording` (kinematic, and keeps every timed trajectory it is
sent: what a real robot's driver would receive). A third-party package registers a
`Backend` subclass under the entry-point group `cramlite.backends`:

    [project.entry-points."cramlite.backends"]
    my-robot = "my_package.driver:MyRobotBackend"

The default (`default_backend`): pybullet if it imports, else mujoco if it imports, else
kinematic; the chosen backend is printed, and stored in every row and trace.
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import Any

from cramlite.backends.base import (
    EXECUTION_CALLS,
    OBSERVATION_CALLS,
    Backend,
    ProcessModules,
    StateObserver,
)
from cramlite.errors import UserInputError
from cramlite.plugins import user_code
from cramlite.world.setup import Setup

ENTRY_POINT_GROUP = "cramlite.backends"
#: Built-in backends by name: (module, class, the module a working install needs).
BUILTIN = {"pybullet": ("cramlite.backends.pybullet", "PyBulletBackend", "pybullet"),
           "mujoco": ("cramlite.backends.mujoco", "MujocoBackend", "mujoco"),
           "kinematic": ("cramlite.backends.kinematic", "KinematicBackend", None),
           "recording": ("cramlite.backends.recording", "RecordingBackend", None)}
#: What to install for a built-in backend whose simulator is missing.
INSTALL_HINT = {"pybullet": "pybullet", "mujoco": "'cramlite[mujoco]'"}
#: The order in which the default is chosen: the first whose simulator imports.
DEFAULT_ORDER = ("pybullet", "mujoco", "kinematic")


def _plugins() -> dict[str, Any]:
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


def installed(name: str) -> bool:
    """Can the backend run here (its simulator installed)? (Looked up, not imported.)"""
    if name in BUILTIN:
        needs = BUILTIN[name][2]
        return needs is None or importlib.util.find_spec(needs) is not None
    return name in _plugins()


def available_backends() -> list[str]:
    """Every backend name known here: built in, then plugins."""
    return list(BUILTIN) + sorted(set(_plugins()) - set(BUILTIN))


def default_backend() -> str:
    """pybullet if it imports, else mujoco if it imports, else kinematic."""
    for name in DEFAULT_ORDER:
        if installed(name):
            return name
    return "kinematic"


def backend_class(name: str) -> type[Backend]:
    """The class of a backend by name (built in or a plugin's entry point)."""
    if name in BUILTIN:
        module, cls, needs = BUILTIN[name]
        if needs is not None and importlib.util.find_spec(needs) is None:
            raise UserInputError(f"the {name} backend needs the {needs} package, which is not "
                                 f"installed here (pip install {INSTALL_HINT.get(name, needs)});"
                                 " expected one of the backends installed: "
                                 f"{', '.join(runnable_backends())}",
                                 field="--backend")
        return getattr(importlib.import_module(module), cls)
    plugins = _plugins()
    if name not in plugins:
        raise UserInputError(f"unknown backend {name!r}; expected one of "
                             f"{', '.join(available_backends())}", field="--backend")
    try:
        user_code()
        loaded = plugins[name].load()
    except Exception as exc:  # a broken plugin: one line, naming it
        raise UserInputError(f"backend {name!r} ({plugins[name].value}) could not be loaded: "
                             f"{type(exc).__name__}: {exc}", field="--backend") from None
    if not (isinstance(loaded, type) and issubclass(loaded, Backend)):
        raise UserInputError(f"backend {name!r} ({plugins[name].value}) is not a "
                             "cramlite.backends.Backend subclass", field="--backend")
    return loaded


def runnable_backends() -> list[str]:
    return [n for n in available_backends() if installed(n)]


def check_backend(name: str) -> str:
    """The name, if that backend can run here; else UserInputError (one line)."""
    backend_class(name)
    return name


def load_backend(name: str, setup: Setup, gui: bool = False) -> Backend:
    """A backend's world for a setup, by the backend's name."""
    cls = backend_class(name)
    if gui:
        if name != "pybullet":
            raise UserInputError(f"the {name} backend has no GUI; expected --backend "
                                 "pybullet with --gui", field="--gui")
        return cls(setup, gui=True)
    return cls(setup)


__all__ = ["EXECUTION_CALLS", "OBSERVATION_CALLS", "Backend", "ProcessModules",
           "StateObserver", "available_backends", "backend_class", "check_backend",
           "default_backend", "installed", "load_backend", "runnable_backends"]
