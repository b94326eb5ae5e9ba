"""The API reference (docs/api.md), generated from the public names' signatures and
docstrings: the designators, the plan language, strategies, plans and backends.

`python -m cramlite.api_reference > docs/api.md` writes it; a test checks the file is what
the code says, so the reference cannot drift from the API.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import re
from typing import Any

HEADER = """# API reference

Generated from the code's own signatures and docstrings (`python -m cramlite.api_reference
> docs/api.md`; a test keeps it in sync). Every name here imports from `cramlite` or from
the module named. The tutorial ([tutorial.md](tutorial.md)) shows them at work.
"""

#: (section, [(module, name)]) in the order the reference shows them.
SECTIONS: list[tuple[str, list[tuple[str, str]]]] = [
    ("Running a plan", [
        ("cramlite.designators", "simulated_robot"), ("cramlite.designators", "RobotContext"),
        ("cramlite.designators", "ExecutionOptions"), ("cramlite.trial", "TrialRunner"),
        ("cramlite.plans", "PlanReport")]),
    ("Action designators", [
        ("cramlite.designators", n) for n in (
            "NavigateAction", "PickUpAction", "PlaceAction", "TransportAction",
            "FetchAction", "DeliverAction", "PickAndPlaceAction", "ParkArmsAction",
            "MoveTorsoAction", "SetGripperAction",
            "LookAtAction", "DetectAction", "ActionDesignator")] + [
        ("cramlite.designators.storage", "OpenAction"),
        ("cramlite.designators.storage", "CloseAction")]),
    ("Object and location designators", [
        ("cramlite.designators", n) for n in (
            "ObjectDesignatorDescription", "CostmapLocation", "PlacingLocation")]),
    ("Motion designators", [
        ("cramlite.designators", n) for n in (
            "MoveMotion", "MoveArmJointsMotion", "MoveTorsoMotion", "MoveGripperMotion",
            "MoveTCPMotion", "AttachMotion", "DetachMotion")]),
    ("The plan language", [
        ("cramlite.designators", n) for n in (
            "Sequential", "TryInOrder", "TryAll", "Parallel", "Repeat", "Code", "Retry",
            "retry", "Monitor", "RobotState", "MonitorFired")]),
    ("Failures", [
        ("cramlite.designators", n) for n in (
            "PlanFailure", "NavigationFailed", "GraspFailed", "PlacementFailed",
            "MotionPlanningFailed", "IKFailed", "ObjectNotFound", "ObjectUnreachable",
            "ContainerManipulationFailed")]),
    ("Ordering strategies", [
        ("cramlite.strategies", n) for n in (
            "Strategy", "Candidate", "make_strategy", "available_strategies")]),
    ("Backends", [
        ("cramlite.backends", n) for n in (
            "ProcessModules", "Backend", "load_backend", "available_backends",
            "default_backend")]),
    ("Failure injection", [
        ("cramlite.designators.injection", n) for n in ("parse_inject", "InjectingModules")]),
]


def _signature(obj: Any) -> str:
    try:
        text = str(inspect.signature(obj))
    except (TypeError, ValueError):
        return "(...)"
    return text.replace("'", "")


def _field_comments(cls: type) -> dict[str, str]:
    """The `#:` comments of a class's fields: on the lines above a field, or after it."""
    try:
        source = inspect.getsource(cls)
    except (OSError, TypeError):
        return {}
    out: dict[str, str] = {}
    above: list[str] = []
    for line in source.splitlines()[1:]:
        text = line.strip()
        if text.startswith("#:"):
            above.append(text[2:].strip())
            continue
        match = re.match(r"([a-z_][a-z0-9_]*)\s*:", text)
        if match and line.startswith("    ") and not line.startswith("     "):
            after = text.split("#:", 1)[1].strip() if "#:" in text else ""
            words = " ".join([*above, after]).strip()
            if words:
                out[match.group(1)] = words
        above = []
    return out


def _fields(cls: type) -> list[str]:
    """A dataclass's fields with their defaults and what their comments (#:) say."""
    comments = _field_comments(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.name.startswith("_") or not f.init:
            continue
        if f.default is not dataclasses.MISSING:
            default = f" = {f.default!r}"
        elif f.default_factory is not dataclasses.MISSING:
            default = " = (a new one)"
        else:
            default = ""
        words = comments.get(f.name, "")
        out.append(f"- `{f.name}`{default}" + (f": {words}" if words else ""))
    return out


def _public_methods(cls: type) -> list[str]:
    out = []
    for name, member in cls.__dict__.items():
        if name.startswith("_") or not callable(member) or isinstance(member, type):
            continue
        doc = inspect.getdoc(member) or ""
        summary = doc.split("\n\n")[0].replace("\n", " ")
        out.append(f"- `{name}{_signature(member)}`" + (f": {summary}" if summary else ""))
    return out


def entry(module: str, name: str) -> str:
    """One name's section: its signature, its docstring, and for a class its fields (a
    dataclass) or its public methods."""
    obj = getattr(importlib.import_module(module), name)
    kind = "class" if isinstance(obj, type) else "function"
    lines = [f"### `{name}`", "", f"`{module}.{name}{_signature(obj)}` ({kind})", ""]
    doc = inspect.getdoc(obj)
    if doc:
        lines += [doc, ""]
    if isinstance(obj, type):
        extra = _fields(obj) if dataclasses.is_dataclass(obj) and not issubclass(
            obj, BaseException) else _public_methods(obj)
        if extra:
            lines += [*extra, ""]
    return "\n".join(lines)


def reference() -> str:
    parts = [HEADER]
    for title, names in SECTIONS:
        parts.append(f"## {title}\n")
        parts += [entry(module, name) for module, name in names]
    return "\n".join(parts).rstrip() + "\n"


if __name__ == "__main__":
    print(reference(), end="")
