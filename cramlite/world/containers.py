"""Closed storage of a world: drawers and cupboards, read from `<world>.containers.yaml`.

A container is a named part of the world: the link that moves (a drawer, a door) on its
joint (0 = closed, `open_value` = open), the handle the robot grasps (a point in the
moving link's frame, and the tool's roll about the approach: a drawer's bar is horizontal,
a door's vertical), and the inside where items rest (a box in a link's frame; its bottom
is what items stand on; for a drawer it moves with the drawer).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from cramlite.errors import SetupError
from cramlite.world.strict_yaml import describe_yaml_error, load_strict

KINDS = ("drawer", "cupboard")
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Container:
    name: str
    kind: str  #: "drawer" (prismatic joint) or "cupboard" (a hinged door)
    link: str  #: the part that moves
    joint: str
    handle: str  #: the handle's link (fixed to `link`)
    grasp: Vec3  #: the grasp point on the handle, in the frame of `link`
    roll: float  #: the tool's roll about the approach when it grasps the handle
    inside_link: str
    inside_min: Vec3  #: the inside, in the frame of `inside_link` (min z: the bottom)
    inside_max: Vec3
    open_value: float  #: joint value when open

    def fits(self, local: Vec3, half_x: float, half_y: float, height: float,
             slack: float = 0.0) -> bool:
        """Does an item standing at `local` (its bottom centre, in the inside link's frame,
        axis-aligned half sizes) fit inside (within `slack` of its walls and top)?"""
        (x0, y0, z0), (x1, y1, z1) = self.inside_min, self.inside_max
        x, y, z = local
        return (x0 - slack <= x - half_x and x + half_x <= x1 + slack
                and y0 - slack <= y - half_y and y + half_y <= y1 + slack
                and abs(z - z0) <= 0.01 and z + height <= z1 + slack)

    def describe_inside(self) -> str:
        """Its inside's size, as messages give it."""
        (x0, y0, z0), (x1, y1, z1) = self.inside_min, self.inside_max
        return f"{x1 - x0:.2f} x {y1 - y0:.2f} m and {z1 - z0:.2f} m tall"


def turned_halves(extents: Sequence[float], yaw: float) -> tuple[float, float]:
    """Half sizes along x and y of the axis-aligned bounds of a box of these extents
    turned by `yaw` about z (a box fits in an axis-aligned one exactly when its bounds
    do)."""
    c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
    ex, ey = extents[0], extents[1]
    return (c * ex + s * ey) / 2, (s * ex + c * ey) / 2


def containers_path(world_urdf: Path) -> Path:
    return world_urdf.with_suffix(".containers.yaml")


def load_containers(world_urdf: Path) -> dict[str, Container]:
    """The containers described beside a world URDF (none if there is no such file)."""
    path = containers_path(world_urdf)
    if not path.exists():
        return {}
    src = str(path)
    try:
        data = load_strict(path.read_text())  # (as setups are read: no repeated keys)
    except yaml.YAMLError as exc:
        message, where = describe_yaml_error(exc)
        raise SetupError(message, source=src, field=where) from None
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise SetupError(f"cannot read containers ({type(exc).__name__})", source=src) from None
    if not isinstance(data, dict) or not isinstance(data.get("containers"), dict):
        raise SetupError("expected a mapping 'containers: {name: {...}}'", source=src)
    return {name: _container(name, spec, src) for name, spec in data["containers"].items()}


def _container(name: str, spec: Any, src: str) -> Container:
    where = f"containers.{name}"

    def fail(field: str, message: str) -> SetupError:
        return SetupError(message, source=src, field=f"{where}.{field}")

    if not isinstance(spec, dict):
        raise SetupError("expected a mapping", source=src, field=where)

    def text(key: str) -> str:
        value = spec.get(key)
        if not isinstance(value, str) or not value:
            raise fail(key, f"expected a name, got {value!r}")
        return value

    def vec(value: Any, key: str) -> Vec3:
        if (not isinstance(value, list) or len(value) != 3
                or not all(isinstance(v, int | float) and math.isfinite(v) for v in value)):
            raise fail(key, f"expected [x, y, z], got {value!r}")
        return (float(value[0]), float(value[1]), float(value[2]))

    kind = text("kind")
    if kind not in KINDS:
        raise fail("kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")
    inside = spec.get("inside")
    if not isinstance(inside, dict):
        raise fail("inside", "expected {link, min, max}")
    opened = spec.get("open")
    if not isinstance(opened, int | float) or not opened > 0:
        raise fail("open", f"expected the joint value when open (> 0), got {opened!r}")
    roll = spec.get("roll", 0.0)
    if not isinstance(roll, int | float):
        raise fail("roll", f"expected radians, got {roll!r}")
    link = inside.get("link")
    if not isinstance(link, str):
        raise fail("inside.link", f"expected a link name, got {link!r}")
    return Container(name=name, kind=kind, link=text("link"), joint=text("joint"),
                     handle=text("handle"), grasp=vec(spec.get("grasp"), "grasp"),
                     roll=float(roll), inside_link=link,
                     inside_min=vec(inside.get("min"), "inside.min"),
                     inside_max=vec(inside.get("max"), "inside.max"),
                     open_value=float(opened))
