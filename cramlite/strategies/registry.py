"""Finding strategies by name: built-ins, plugins (entry points), `module:Class` paths.

Third-party packages register a `Strategy` subclass under the entry-point group
`cramlite.strategies`, e.g. in their pyproject.toml:

    [project.entry-points."cramlite.strategies"]
    my-order = "my_package.order:MyStrategy"

Built-in and entry-point names are *registered*: anyone may name them, including an
ordering request from another process. A `package.module:Class` or `path/to/file.py:Class` path
imports code (see `cramlite.plugins`: also from the current folder), so only a
command-line option may use it (`registered_only=True` refuses it).
"""

from __future__ import annotations

from typing import Any

from cramlite.errors import UserInputError
from cramlite.plugins import load_reference, user_code
from cramlite.strategies.base import Strategy, StrategyError
from cramlite.strategies.batch import (
    NearestBatchStrategy,
    OPMBatchStrategy,
    OptimalBatchStrategy,
    RandomBatchStrategy,
)
from cramlite.strategies.opm import NearestStrategy, OPMStrategy, OPMTwoStepStrategy
from cramlite.strategies.optimal import OptimalStrategy
from cramlite.strategies.simple import BaselineStrategy, RandomStrategy

ENTRY_POINT_GROUP = "cramlite.strategies"
BUILTIN: dict[str, type[Strategy]] = {cls.name: cls for cls in (
    OPMStrategy, BaselineStrategy, RandomStrategy, NearestStrategy, OPMTwoStepStrategy,
    OptimalStrategy, OPMBatchStrategy, NearestBatchStrategy, OptimalBatchStrategy,
    RandomBatchStrategy)}


def plugin_entry_points() -> dict[str, Any]:
    from importlib.metadata import entry_points  # ~15 ms: only when a plugin is looked up

    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


LEARNED_PREFIX = "learned:"


def available_strategies() -> dict[str, str]:
    """Name -> one-line summary of every registered strategy (built-in or plugin)."""
    out = {name: cls.summary for name, cls in BUILTIN.items()}
    out[f"{LEARNED_PREFIX}MODEL"] = "a model file written by `cramlite train` (RNN, NN, CPT)"
    for name, ep in plugin_entry_points().items():
        try:
            user_code()
            cls = ep.load()
            summary = getattr(cls, "summary", "") or "(no summary)"
            out.setdefault(name, f"{summary} (plugin {ep.value})")
        except Exception as exc:  # a broken plugin is listed, with why
            out.setdefault(name, f"plugin {ep.value}: cannot load: {type(exc).__name__}: "
                                 f"{exc}")
    return out


def strategy_class(name: str, *, registered_only: bool = False) -> type[Strategy]:
    """Resolve a strategy name, an entry-point name, or (unless `registered_only`)
    `package.module:Class`."""
    if name in BUILTIN:
        return BUILTIN[name]
    if name.startswith(LEARNED_PREFIX):  # a trained model; numpy (and cpt) only when used
        if registered_only:  # a request must not make the service read files
            raise StrategyError(f"{name!r}: a request may not name a model file; give it on "
                                "the command line (cramlite order --strategy "
                                f"{name}) and leave 'strategy' out of the request")
        from cramlite.learning.strategy import learned_class

        try:
            return learned_class(name[len(LEARNED_PREFIX):])
        except UserInputError as exc:
            raise StrategyError(str(exc)) from None
    plugins = plugin_entry_points()
    try:
        if name in plugins:
            user_code()
            cls = plugins[name].load()
        elif ":" in name and not registered_only:
            # (a file path or a module, also from the current folder: see cramlite.plugins)
            cls = load_reference(name, "strategy", "--strategy")
        elif ":" in name:
            raise StrategyError(f"{name!r} is not a registered strategy; a request may name "
                                f"only {', '.join(available_strategies())} (a module:Class "
                                "path is a command-line option, e.g. cramlite order "
                                "--strategy)")
        else:
            raise StrategyError(f"unknown strategy {name!r}; expected one of "
                                f"{', '.join(available_strategies())} or package.module:Class")
    except StrategyError:
        raise
    except UserInputError as exc:
        raise StrategyError(exc.detail) from None
    except Exception as exc:  # ImportError, AttributeError, or anything a plugin's import raises
        raise StrategyError(f"cannot load strategy {name!r}: {type(exc).__name__}: {exc}") \
            from None
    if not (isinstance(cls, type) and issubclass(cls, Strategy)):
        raise StrategyError(f"strategy {name!r} is not a cramlite.strategies.Strategy subclass")
    return cls


def ignores_params(name: str, *, registered_only: bool = False) -> bool:
    """Whether the strategy takes no OPM parameters (its class says `uses_params = False`):
    parameters given to it would be ignored, which the command line and the ordering
    service refuse rather than run past."""
    return not getattr(strategy_class(name, registered_only=registered_only), "uses_params",
                       True)


def make_strategy(name: str, *, registered_only: bool = False, **kwargs: Any) -> Strategy:
    """A fresh strategy instance (one per episode or trial). A plugin whose constructor
    fails is reported as a StrategyError naming it."""
    cls = strategy_class(name, registered_only=registered_only)
    try:
        return cls(**kwargs)
    except StrategyError:
        raise
    except Exception as exc:
        raise StrategyError(f"strategy {name!r} ({cls.__module__}.{cls.__qualname__}) could "
                            f"not be created: {type(exc).__name__}: {exc}") from exc
