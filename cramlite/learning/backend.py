"""Importing the learning libraries: one-line errors without the extra, and a
single-threaded, repeatable keras on jax's CPU backend."""

from __future__ import annotations

import contextlib
import os
from types import ModuleType

from cramlite.errors import UserInputError

INSTALL_HINT = "install the learn extra: pip install 'cramlite[learn]'"


class MissingExtraError(UserInputError):
    """A learning library is not installed."""


def keras() -> ModuleType:
    """keras 3 on jax's CPU backend, single-threaded (set before the first import)."""
    os.environ.setdefault("KERAS_BACKEND", "jax")
    os.environ.setdefault("JAX_PLATFORMS", "cpu")
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_cpu_multi_thread_eigen" not in flags:
        os.environ["XLA_FLAGS"] = (flags + " --xla_cpu_multi_thread_eigen=false").strip()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "3")
    try:
        import keras as module
    except ImportError:
        raise MissingExtraError(f"training needs keras and jax; {INSTALL_HINT}") from None
    if module.backend.backend() != "jax":
        raise MissingExtraError(f"keras runs on {module.backend.backend()!r}; cramlite trains "
                                "on jax: set KERAS_BACKEND=jax") from None
    return module


def cpt_class() -> type:
    try:
        from cpt.cpt import Cpt
    except ImportError:
        raise MissingExtraError(f"CPT models need the `cpt` package; {INSTALL_HINT}") from None
    return Cpt


def versions() -> dict[str, str]:
    """Versions of the libraries a model was made with (for its metadata)."""
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for name in ("cramlite", "numpy", "keras", "jax", "jaxlib", "cpt"):
        with contextlib.suppress(PackageNotFoundError):
            out[name] = version(name)
    return out
