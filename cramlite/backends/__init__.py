"""Backends: what executes a plan. Each implements `ProcessModules` (the seam a simulator
or a real robot implements) and loads its world from a setup; planning never touches it
(it asks the planning scene, which the process modules' reports keep up to date)."""

from __future__ import annotations

from cramlite.backends.base import (
    EXECUTION_CALLS,
    OBSERVATION_CALLS,
    Backend,
    ProcessModules,
    StateObserver,
)
from cramlite.world.setup import Setup

#: Built-in backends, by name: the module and class that implement them.
BUILTIN = {"pybullet": ("cramlite.backends.pybullet", "PyBulletBackend")}


def available_backends() -> list[str]:
    return sorted(BUILTIN)


def default_backend() -> str:
    return "pybullet"


def load_backend(name: str, setup: Setup, gui: bool = False) -> Backend:
    """A backend's world for a setup, by the backend's name."""
    import importlib

    if name not in BUILTIN:
        raise ValueError(f"unknown backend {name!r}; expected one of "
                         f"{', '.join(available_backends())}")
    module, cls = BUILTIN[name]
    backend_class = getattr(importlib.import_module(module), cls)
    if gui:
        return backend_class(setup, gui=True)
    return backend_class(setup)


__all__ = ["EXECUTION_CALLS", "OBSERVATION_CALLS", "Backend", "ProcessModules",
           "StateObserver", "available_backends", "default_backend", "load_backend"]
