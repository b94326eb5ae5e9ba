"""Finding plans by name: built-ins, plugins (entry points), `module:function` and
`path/to/file.py:function`.

A plan is a function `plan(ctx, setup, strategy) -> PlanReport` written with designators
(see `plans/set_table.py` and `examples/fetch_two.py`). Third-party packages register one
under the entry-point group `cramlite.plans`, e.g. in their pyproject.toml:

    [project.entry-points."cramlite.plans"]
    fetch-two = "my_package.plans:fetch_two"

The built-in plans' success is the trial's check of where the items ended (setting the
table: at their targets; clearing up: back in their containers or on the counter); a
user's plan says what success means by setting `PlanReport.success` (left None: success
is "no failures").
"""

from __future__ import annotations

import inspect
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cramlite.errors import UserInputError
from cramlite.plugins import file_hash, is_code_reference, load_reference, user_code

ENTRY_POINT_GROUP = "cramlite.plans"
BUILTIN_PLANS = ("set-table", "clear-table")

Plan = Callable[..., Any]


class PlanCrashed(Exception):
    """A user's plan raised something else than a PlanFailure: a bug in it, named with
    where in the user's code it happened (one line for the command line)."""


def crashed(name: str, exc: BaseException) -> PlanCrashed:
    """The PlanCrashed that names plan `name`, what it raised and the last line of code
    outside cramlite that it ran (the user's own, where the bug most likely is)."""
    package = Path(__file__).resolve().parent
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if Path(f.filename).is_file()  # (not "<string>": a dataclass's own __init__)
              and not Path(f.filename).resolve().is_relative_to(package)]
    where = f" (at {frames[-1].filename}, line {frames[-1].lineno})" if frames else ""
    return PlanCrashed(f"plan {name} raised {type(exc).__name__}: {exc}{where}")


def _builtins() -> dict[str, Plan]:
    from cramlite.plans import PLANS

    return dict(PLANS)


def plugin_entry_points() -> dict[str, Any]:
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}


def summary_of(obj: Any) -> str:
    """The first sentence of an object's docstring (or of its module's)."""
    doc = inspect.getdoc(obj) or inspect.getdoc(inspect.getmodule(obj)) or ""
    paragraph = " ".join(doc.strip().split("\n\n")[0].split())
    if not paragraph:
        return "(no docstring)"
    end = paragraph.find(". ")
    return paragraph if end < 0 else paragraph[:end + 1]


def available_plans() -> dict[str, str]:
    """Name -> one-line summary of every registered plan (built-in or plugin)."""
    out = {name: summary_of(plan) for name, plan in _builtins().items()}
    for name, ep in plugin_entry_points().items():
        try:
            user_code()
            out.setdefault(name, f"{summary_of(ep.load())} (plugin {ep.value})")
        except Exception as exc:  # a broken plugin is listed, with why
            out.setdefault(name, f"plugin {ep.value}: cannot load: {type(exc).__name__}: "
                                 f"{exc}")
    return out


def plan_function(name: str, field: str = "--plan") -> Plan:
    """The plan a name stands for; UserInputError naming `field` if there is none."""
    builtins = _builtins()
    if name in builtins:
        return builtins[name]
    plugins = plugin_entry_points()
    if name in plugins:
        try:
            user_code()
            plan = plugins[name].load()
        except Exception as exc:
            raise UserInputError(f"cannot load plan {name!r} ({plugins[name].value}): "
                                 f"{type(exc).__name__}: {exc}", field=field) from None
    elif is_code_reference(name):
        plan = load_reference(name, "plan", field)
    else:
        raise UserInputError(f"unknown plan {name!r}; expected one of "
                             f"{', '.join(available_plans())}, package.module:function or "
                             "path/to/file.py:function", field=field)
    if not callable(plan):
        raise UserInputError(f"plan {name!r} is not a function (ctx, setup, strategy) -> "
                             "PlanReport", field=field)
    _check_signature(name, plan, field)
    return plan


def _check_signature(name: str, plan: Plan, field: str) -> None:
    """A plan is called with three arguments (ctx, setup, strategy): one that cannot take
    them (a strategy class given as a plan, a function of two arguments) is refused here,
    in one line, not with a traceback from inside the trial."""
    try:
        signature = inspect.signature(plan)
    except (TypeError, ValueError):  # (a builtin without one: called as it is)
        return
    try:
        signature.bind(None, None, None)
    except TypeError:
        what = "a class" if inspect.isclass(plan) else f"a function {signature}"
        raise UserInputError(f"plan {name!r} is {what}; expected a function (ctx, setup, "
                             "strategy) -> PlanReport", field=field) from None


def is_builtin(name: str) -> bool:
    """A plan of `cramlite.plans.PLANS` (success: the trial's check of the items)."""
    return name in _builtins()


def plan_hash(name: str) -> str:
    """What identifies a plan's code beyond its name: its file's hash, for a plan given as
    a file ("" otherwise)."""
    return file_hash(name) if is_code_reference(name) else ""
