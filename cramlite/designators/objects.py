"""Object designators: describe an object by name and/or type, resolve it in the planning
scene (what the robot believes is there)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from cramlite.designators.context import RobotContext
from cramlite.designators.failures import ObjectNotFound
from cramlite.scene.transforms import Quat, Vec3


@dataclass(frozen=True)
class ObjectDesignator:
    """A resolved object: a concrete item of the world."""

    name: str
    type: str

    def pose(self, ctx: RobotContext) -> tuple[Vec3, Quat]:
        return ctx.scene.object_pose(self.name)

    def height_m(self, ctx: RobotContext) -> float:
        return ctx.scene.items[self.name].height()

    def is_round(self, ctx: RobotContext) -> bool:
        """A cylinder: turning it about its axis changes nothing."""
        return ctx.scene.items[self.name].is_round()

    def radius_m(self, ctx: RobotContext) -> float:
        """Half the diagonal of the object's footprint (a circle that covers it)."""
        x, y, _ = ctx.scene.items[self.name].extents
        return 0.5 * float((x**2 + y**2) ** 0.5)


@dataclass(frozen=True)
class ObjectDesignatorDescription:
    """Objects with one of `names` and one of `types` (None: any)."""

    names: Sequence[str] | None = None
    types: Sequence[str] | None = None

    def ground(self, ctx: RobotContext) -> Iterator[ObjectDesignator]:
        for name, obj in ctx.scene.items.items():
            if self.names is not None and name not in self.names:
                continue
            if self.types is not None and obj.type not in self.types:
                continue
            yield ObjectDesignator(name, obj.type)

    def resolve(self, ctx: RobotContext) -> ObjectDesignator:
        for designator in self.ground(ctx):
            return designator
        what = ", ".join(filter(None, [f"names {list(self.names)}" if self.names else "",
                                       f"types {list(self.types)}" if self.types else ""]))
        raise ObjectNotFound(f"no object with {what or 'any description'} in the world",
                             obj=(self.names or self.types or [None])[0])


def as_object(obj: ObjectDesignator | ObjectDesignatorDescription | str,
              ctx: RobotContext) -> ObjectDesignator:
    if isinstance(obj, ObjectDesignator):
        return obj
    if isinstance(obj, str):
        obj = ObjectDesignatorDescription(names=[obj])
    return obj.resolve(ctx)
