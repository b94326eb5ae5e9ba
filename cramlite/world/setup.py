"""Setup files: a world, the robot's start pose, the items and where they go.

A setup is YAML (see worlds/setups/v1.yaml, commented); this module parses and
validates it without touching PyBullet, so that every mistake is reported with the
file, the field and what was expected. Geometry checks (an item inside another body,
an item off its surface) happen when a `World` loads the setup.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cramlite.errors import SetupError
from cramlite.resources import worlds_dir

#: Relational-dependency categories of the OPM (SPEC section 1); "none" means k = 1.
CATEGORIES = ("strong", "mid", "food", "none")
SETUP_FORMAT = 1

ITEM_KEYS = {"name", "type", "pose", "surface", "in", "contained", "category", "target",
             "aliases"}
TOP_KEYS = {"format", "name", "description", "world", "robot", "items", "baseline_order"}


def builtin_setup_names() -> list[str]:
    return sorted(p.stem for p in (worlds_dir() / "setups").glob("*.yaml"))


@dataclass(frozen=True)
class Pose:
    """A pose on a surface: position (z = bottom face of the item) and yaw in radians."""

    x: float
    y: float
    z: float
    yaw: float = 0.0

    @property
    def xyz(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)


@dataclass(frozen=True)
class ItemSpec:
    name: str
    type: str
    urdf: Path
    pose: Pose
    surface: str  #: the link it stands on (for an item in a container: the container's)
    target: Pose
    contained: bool = False
    category: str = "none"
    #: Other names of the item (a learned strategy maps `breakfast-cereal` to `cereal`).
    aliases: tuple[str, ...] = ()
    #: The closed container (drawer, cupboard) it is stored in, if any (`in:` in the file).
    container: str | None = None


@dataclass(frozen=True)
class RobotStart:
    x: float
    y: float
    yaw: float


@dataclass(frozen=True)
class Setup:
    """A validated setup file."""

    name: str
    source: Path
    world_urdf: Path
    robot_start: RobotStart
    items: tuple[ItemSpec, ...]
    baseline_order: tuple[str, ...]
    description: str = ""
    raw: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def item(self, name: str) -> ItemSpec:
        for spec in self.items:
            if spec.name == name:
                return spec
        raise KeyError(name)


def resolve_setup_path(setup: str | Path) -> Path:
    """`v1`..`v5` (or any shipped setup name) or a path to a YAML file."""
    text = str(setup)
    shipped = worlds_dir() / "setups" / f"{text}.yaml"
    if shipped.exists():
        return shipped
    path = Path(text)
    if path.exists():
        return path
    raise SetupError(
        f"no such setup file; expected a path or one of {', '.join(builtin_setup_names())}",
        source=text,
    )


def load_setup(setup: str | Path) -> Setup:
    """Read and validate a setup file (by shipped name or path)."""
    path = resolve_setup_path(setup)
    src = str(path)
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else None
        problem = getattr(exc, "problem", None) or "could not parse"
        raise SetupError(f"malformed YAML ({problem}); expected a YAML mapping",
                         source=src, field=where) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SetupError(f"cannot read file ({exc.__class__.__name__})", source=src) from None
    return parse_setup(data, path)


def parse_setup(data: Any, path: Path) -> Setup:
    src = str(path)

    def fail(fld: str, msg: str) -> SetupError:
        return SetupError(msg, source=src, field=fld)

    if not isinstance(data, dict):
        raise fail("(top level)", f"expected a mapping with keys {sorted(TOP_KEYS)}, "
                                  f"got {type(data).__name__}")
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise fail(sorted(unknown)[0], f"unknown key; expected one of {sorted(TOP_KEYS)}")
    fmt = data.get("format", SETUP_FORMAT)
    if fmt != SETUP_FORMAT:
        raise fail("format", f"expected {SETUP_FORMAT}, got {fmt!r}")
    name = data.get("name", path.stem)
    if not isinstance(name, str) or not name:
        raise fail("name", f"expected a non-empty string, got {name!r}")

    world = data.get("world")
    if not isinstance(world, str) or not world:
        raise fail("world", "expected the name of a world in worlds/ (e.g. kitchen) or a path "
                            "to a URDF")
    world_urdf = _resolve_urdf(world, path, worlds_dir())
    if world_urdf is None:
        raise fail("world", f"expected worlds/{world}.urdf or a URDF path; found neither")

    robot = data.get("robot")
    if not isinstance(robot, dict) or "start" not in robot:
        raise fail("robot", "expected a mapping with 'start: [x, y, yaw]'")
    start = _numbers(robot["start"], 3, "robot.start", "[x, y, yaw]", fail)
    robot_start = RobotStart(*start)

    raw_items = data.get("items")
    if not isinstance(raw_items, list) or not raw_items:
        raise fail("items", "expected a non-empty list of items")
    items = tuple(_parse_item(raw, i, path, fail) for i, raw in enumerate(raw_items))
    names = [it.name for it in items]
    for i, nm in enumerate(names):
        if nm in names[:i]:
            raise fail(f"items[{i}].name", f"duplicate item name {nm!r}; names must be unique")

    order = data.get("baseline_order", names)
    if not isinstance(order, list) or sorted(map(str, order)) != sorted(names):
        raise fail("baseline_order", f"expected a permutation of the item names {names}, "
                                     f"got {order!r}")
    return Setup(name=name, source=path, world_urdf=world_urdf, robot_start=robot_start,
                 items=items, baseline_order=tuple(map(str, order)),
                 description=str(data.get("description", "")), raw=data)


def _parse_item(raw: Any, i: int, path: Path, fail) -> ItemSpec:
    where = f"items[{i}]"
    if not isinstance(raw, dict):
        raise fail(where, f"expected a mapping with keys {sorted(ITEM_KEYS)}")
    unknown = set(raw) - ITEM_KEYS
    if unknown:
        raise fail(f"{where}.{sorted(unknown)[0]}", f"unknown key; expected one of "
                                                    f"{sorted(ITEM_KEYS)}")
    for key in ("name", "pose", "target"):
        if key not in raw:
            raise fail(f"{where}.{key}", "missing; every item needs name, pose, target and "
                                         "surface (or in: a container)")
    if ("surface" in raw) == ("in" in raw):
        raise fail(f"{where}.surface", "expected either 'surface: <link it stands on>' or "
                                       "'in: <container>', not both or neither")
    name = raw["name"]
    if not isinstance(name, str) or not name:
        raise fail(f"{where}.name", f"expected a non-empty string, got {name!r}")
    item_type = raw.get("type", name)
    if not isinstance(item_type, str):
        raise fail(f"{where}.type", f"expected a string, got {item_type!r}")
    urdf = _resolve_urdf(item_type, path, worlds_dir() / "items")
    if urdf is None:
        known = sorted(p.stem for p in (worlds_dir() / "items").glob("*.urdf"))
        raise fail(f"{where}.type", f"unknown item type {item_type!r}; expected one of {known} "
                                    "or a path to a URDF")
    pose = Pose(*_numbers(raw["pose"], 4, f"{where}.pose", "[x, y, z, yaw]", fail))
    target = Pose(*_numbers(raw["target"], 4, f"{where}.target", "[x, y, z, yaw]", fail))
    container = raw.get("in")
    if container is not None and (not isinstance(container, str) or not container):
        raise fail(f"{where}.in", f"expected the name of a container, got {container!r}")
    surface = raw.get("surface", container)
    if not isinstance(surface, str) or not surface:
        raise fail(f"{where}.surface", f"expected the name of a world link, got {surface!r}")
    contained = raw.get("contained", container is not None)
    if not isinstance(contained, bool):
        raise fail(f"{where}.contained", f"expected true or false, got {contained!r}")
    if contained != (container is not None):
        raise fail(f"{where}.contained", "follows from 'in:' (items in a container are "
                                         f"contained, the others not); expected "
                                         f"{str(container is not None).lower()} or no key")
    category = raw.get("category", "none")
    if category is None:
        category = "none"
    if category not in CATEGORIES:
        raise fail(f"{where}.category", f"unknown category {category!r}; expected one of "
                                        f"{', '.join(CATEGORIES)}")
    aliases = raw.get("aliases") or []
    if not isinstance(aliases, list) or not all(isinstance(a, str) and a for a in aliases):
        raise fail(f"{where}.aliases", f"expected a list of names, got {aliases!r}")
    return ItemSpec(name=name, type=item_type, urdf=urdf, pose=pose, surface=surface,
                    target=target, contained=contained, category=category,
                    aliases=tuple(aliases), container=container)


def _numbers(value: Any, n: int, fld: str, shape: str, fail) -> tuple[float, ...]:
    if not isinstance(value, list | tuple):
        raise fail(fld, f"expected {n} numbers {shape}, got {value!r}")
    if len(value) != n:
        raise fail(fld, f"expected {n} numbers {shape}, got {len(value)}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise fail(fld, f"expected {n} finite numbers {shape}, got {value!r}")
        out.append(float(v))
    return tuple(out)


def _resolve_urdf(name: str, setup_path: Path, folder: Path) -> Path | None:
    for candidate in (folder / f"{name}.urdf", setup_path.parent / name, Path(name)):
        if candidate.suffix == ".urdf" and candidate.is_file():
            return candidate.resolve()
    return None
