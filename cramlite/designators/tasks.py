"""The task tree: every action and motion a plan performs, with its robot-time span.

Like PyCRAM's task tree: each `perform` of an action or motion designator becomes a node
(name, the object it concerns, start and end in robot time, succeeded or failed with
the failure) under the action that called it. A failed candidate that a designator
falls through stays in the tree, marked failed, so a user sees what was tried.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from cramlite.errors import bounded_text


@dataclass
class TaskNode:
    name: str
    object: str | None
    start_s: float
    end_s: float | None = None
    status: str = "running"  #: "running", "succeeded" or "failed"
    failure: dict[str, str] | None = None
    children: list[TaskNode] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "object": self.object, "start_s": round(self.start_s, 6),
                "end_s": None if self.end_s is None else round(self.end_s, 6),
                "status": self.status, "failure": self.failure,
                "children": [c.as_dict() for c in self.children]}

    def walk(self) -> Iterator[TaskNode]:
        yield self
        for child in self.children:
            yield from child.walk()


class TaskTree:
    """Records nodes as designators perform; `clock()` gives the current robot time."""

    def __init__(self, clock: Callable[[], float]):
        self.clock = clock
        self.roots: list[TaskNode] = []
        self._stack: list[TaskNode] = []

    @contextlib.contextmanager
    def node(self, name: str, obj: str | None = None) -> Iterator[TaskNode]:
        node = TaskNode(name, obj, self.clock())
        (self._stack[-1].children if self._stack else self.roots).append(node)
        self._stack.append(node)
        try:
            yield node
        except BaseException as exc:
            node.status = "failed"
            node.failure = {"type": type(exc).__name__, "message": bounded_text(str(exc))}
            raise
        else:
            node.status = "succeeded"
        finally:
            node.end_s = self.clock()
            self._stack.pop()

    def open_nodes(self) -> list[TaskNode]:
        """The nodes in progress, outermost first."""
        return list(self._stack)

    def current_action(self) -> tuple[str, str | None] | None:
        """The innermost action in progress and the object it (or an enclosing action)
        manipulates."""
        actions = [n for n in self._stack if n.name.endswith("Action")]
        if not actions:
            return None
        obj = next((n.object for n in reversed(actions) if n.object), None)
        return actions[-1].name, obj

    def as_list(self) -> list[dict[str, Any]]:
        return [node.as_dict() for node in self.roots]


def object_name(designator: Any) -> str | None:
    """The name of the object a designator's field refers to, if it can be told."""
    if designator is None:
        return None
    if isinstance(designator, str):
        return designator
    name = getattr(designator, "name", None)
    if isinstance(name, str):
        return name
    names = getattr(designator, "names", None)
    return names[0] if names else None


def recorded(perform: Callable) -> Callable:
    """Decorator for `perform(self, ctx)`: the call becomes a node of `ctx.tasks`."""

    @functools.wraps(perform)
    def wrapper(self, ctx, *args, **kwargs):
        obj = object_name(getattr(self, "object", None) or getattr(self, "obj", None)
                          or getattr(self, "container", None))
        with ctx.tasks.node(type(self).__name__, obj):
            return perform(self, ctx, *args, **kwargs)

    return wrapper


class ActionDesignator:
    """The base of every action designator (a template method): `perform(ctx)` records
    the action as a node of the task tree, runs `execute(ctx)` and then `validate(ctx,
    result)`, the action's post-condition (raise a PlanFailure if it does not hold).
    Subclasses implement `execute` (and `validate`), never `perform`: a post-condition
    cannot be skipped (in PyCRAM nothing calls an action's `validate()`)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "perform" in cls.__dict__:
            raise TypeError(f"{cls.__name__} defines perform(); an action implements "
                            "execute(ctx) and validate(ctx, result), and perform() runs both "
                            "(so the post-condition always runs)")

    def perform(self, ctx: Any) -> Any:
        obj = object_name(getattr(self, "object", None) or getattr(self, "obj", None)
                          or getattr(self, "container", None))
        with ctx.tasks.node(type(self).__name__, obj):
            result = self.execute(ctx)
            self.validate(ctx, result)
            return result

    def execute(self, ctx: Any) -> Any:
        raise NotImplementedError(f"{type(self).__name__} implements no execute(ctx)")

    def validate(self, ctx: Any, result: Any = None) -> None:
        """The action's post-condition (none by default)."""


def actions_only(nodes: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """A task tree (as dictionaries) without its motion nodes: the actions, for reports."""
    return [{**node, "children": actions_only(node["children"])} for node in nodes
            if not node["name"].endswith("Motion")]


def time_in(nodes: list[dict[str, Any]], names: tuple[str, ...]) -> float:
    """Robot time spent in nodes with one of `names` (outermost ones, not counted twice)."""
    total = 0.0
    for node in nodes:
        if node["name"] in names and node["end_s"] is not None:
            total += node["end_s"] - node["start_s"]
        else:
            total += time_in(node["children"], names)
    return total
